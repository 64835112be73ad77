"""Cost of stepping from Python: the same 10k-spring cloth steps timed by Google Benchmark in C++
(build/bench/hooke_bench_simulation: Simulation with swapped state buffers, as hooke run steps,
and with stable ones, which the module uses while a numpy view of x or v is alive) and by a loop of
sim.step() calls in Python holding no view, in one run; prints them and the ratios.

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


def python_step_us(method, steps):
    scene = hooke.load_scene(SCENE, {"mesh.nx": 42, "mesh.ny": 42, "integrator.method": method,
                                     "time.dt": 5e-4})
    sim = hooke.Simulation(scene)
    for _ in range(200):
        sim.step()
    blocks = []
    for _ in range(5):
        t0 = time.perf_counter()
        for _ in range(steps):
            sim.step()
        blocks.append((time.perf_counter() - t0) / steps * 1e6)
    return statistics.median(blocks)


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
    for method, steps in (("symplectic-euler", 2000), ("implicit", 100)):
        py = python_step_us(method, steps)
        swapped, stable = cxx[f"{method}, swapped buffers"], cxx[f"{method}, stable buffers"]
        print(f"{method:17s} C++ {swapped:9.1f} us/step (swapped buffers), {stable:9.1f} (stable); "
              f"Python {py:9.1f} us/step: {py / stable:.3f}x stable, {py / swapped:.3f}x swapped")


if __name__ == "__main__":
    main()
