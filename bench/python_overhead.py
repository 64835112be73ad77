"""Cost of stepping from Python: the same 10k-spring cloth steps timed by Google Benchmark in C++
(build/bench/hooke_bench_simulation: Simulation with swapped state buffers, as hooke run steps,
and with stable ones, which the module uses while a numpy view of x or v is alive) and by a loop of
sim.step() calls in Python holding no view, in one run; prints them and the ratios, and the cost
of a whole sim.step() call on a 4-particle cloth, an upper bound on the per-call overhead that
the noise of a shared machine does not blur.

Usage (from the source tree, after make build):
    PYTHONPATH=build/python /usr/bin/python3 bench/python_overhead.py [build/bench/hooke_bench_simulation]
"""
import json
import os
import statistics
import subprocess
import sys
import time

import hooke

HERE = os.path.dirname(os.path.abspath(__file__))
SCENE = os.path.join(HERE, "..", "problems", "scenes", "hanging_cloth_16.toml")


def median_step_us(overrides, warm, steps):
    """Median over 5 blocks of `steps` sim.step() calls (us per call) on the cloth scene with
    `overrides`, after `warm` steps."""
    sim = hooke.Simulation(hooke.load_scene(SCENE, overrides))
    for _ in range(warm):
        sim.step()
    blocks = []
    for _ in range(5):
        t0 = time.perf_counter()
        for _ in range(steps):
            sim.step()
        blocks.append((time.perf_counter() - t0) / steps * 1e6)
    return statistics.median(blocks)


def python_step_us(method, steps):
    return median_step_us({"mesh.nx": 42, "mesh.ny": 42, "integrator.method": method,
                           "time.dt": 5e-4}, 200, steps)


def call_cost_us(calls=20000):
    """Upper bound on the fixed cost of a sim.step() call from Python: the whole call on a 2 x 2
    cloth (4 particles), whose C++ step is a small part of it."""
    return median_step_us({"mesh.nx": 2, "mesh.ny": 2, "integrator.method": "symplectic-euler",
                           "time.dt": 1e-5}, 1000, calls)


def main():
    binary = sys.argv[1] if len(sys.argv) > 1 else os.path.join(HERE, "..", "build", "bench",
                                                                 "hooke_bench_simulation")
    out = subprocess.run([binary, "--benchmark_format=json", "--benchmark_repetitions=5",
                          "--benchmark_report_aggregates_only=true"],
                         check=True, capture_output=True, text=True).stdout
    cxx = {}
    for b in json.loads(out)["benchmarks"]:
        if b.get("aggregate_name") == "median":
            cxx[b["label"]] = b["real_time"]
    print(f"load average {os.getloadavg()[0]:.2f}; OMP_NUM_THREADS={os.environ.get('OMP_NUM_THREADS', '')}")
    call = call_cost_us()
    print(f"a whole sim.step() call on a 2 x 2 cloth: {call:.2f} us (bounds the per-call overhead)")
    for method, steps in (("symplectic-euler", 2000), ("implicit", 100)):
        py = python_step_us(method, steps)
        swapped, stable = cxx[f"{method}, swapped buffers"], cxx[f"{method}, stable buffers"]
        print(f"{method:17s} C++ {swapped:9.1f} us/step (swapped buffers), {stable:9.1f} (stable); "
              f"Python {py:9.1f} us/step: {py / stable:.3f}x stable, {py / swapped:.3f}x swapped; "
              f"call cost / C++ step {call / swapped:.4f}")


if __name__ == "__main__":
    main()
