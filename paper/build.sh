#!/usr/bin/env bash
# Rebuilds the paper from scratch: runs the four experiments into OUT (default size, or the
# paper's size with --full), records the machine and the timings, assembles OUT/paper.md from
# paper/paper.md (every table and figure is a file the experiments wrote) and renders
# OUT/paper.html with pandoc (figures embedded).
# Usage: paper/build.sh HOOKE_BINARY OUT [--full]      (`make paper`, `make paper FULL=1`)
set -euo pipefail
# The studies factor small matrices (8 x 8 .. 16 x 16 cloths) thousands of times: OpenBLAS threads
# only add overhead there, and on a shared 2-core machine they cost up to 6x in wall time
# (stability: 716 s with the default threads under load, 116 s with one thread on a quiet machine).
# machine.md records the value used.
export OPENBLAS_NUM_THREADS=${OPENBLAS_NUM_THREADS:-1}
hooke=$(realpath "$1")
out=$2
shift 2
size=("$@")
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$out"
out=$(realpath "$out")

echo "experiment,seconds" > "$out/timings.csv"
run() {  # run NAME ARGS...: one experiment, timed
  local name=$1
  shift
  local t0
  t0=$(date +%s%N)
  echo "paper: hooke $name ${size[*]:-} ..."
  "$hooke" "$name" "${size[@]}" --out "$out/$name" "$@"
  echo "$name,$(( ($(date +%s%N) - t0) / 1000000 ))e-3" >> "$out/timings.csv"
}
run stability
run workprecision
# Error control over a longer time: the methods swept over rtol, every case to 2 s.
t0=$(date +%s%N)
echo "paper: hooke workprecision --duration 2 (error control) ..."
"$hooke" workprecision "${size[@]}" --methods dopri5-adaptive,bs32-adaptive,implicit-adaptive,implicit-midpoint-adaptive,bdf2-adaptive,cvode,ida --duration 2 \
  --repeat 1 --out "$out/tolerance-2s"
echo "workprecision --duration 2,$(( ($(date +%s%N) - t0) / 1000000 ))e-3" >> "$out/timings.csv"
run resolution
# The runs behind the stability section's "single-k dips": beta = 1/2 and backward Euler (beta 1)
# on the 8 x 8 cloth at h = 0.1 s over 10 s, at three stiffnesses (shear 0.2 k, flexion 0.02 k).
# A run that stops (exit 3) is listed as stopped; assemble.py reads the log.csv files.
t0=$(date +%s%N)
echo "paper: hooke run hanging_cloth_16 (8 x 8, h = 0.1 s, beta 1/2 and 1) ..."
for k in 1e3 1e4 1e5; do
  for beta in 0.5 1; do
    "$hooke" run "$here/../problems/scenes/hanging_cloth_16.toml" --out "$out/dips/k$k-beta$beta" \
      --no-progress --set mesh.nx=8 --set mesh.ny=8 --set springs.structural_stiffness=$k \
      --set springs.shear_stiffness="$(awk "BEGIN{print 0.2 * $k}")" \
      --set springs.flexion_stiffness="$(awk "BEGIN{print 0.02 * $k}")" \
      --set integrator.method=implicit --set integrator.beta=$beta --set time.dt=0.1 \
      --set time.duration=10 --set output.vtk=false --set output.png=false > /dev/null || true
  done
done
echo "dips (6 runs),$(( ($(date +%s%N) - t0) / 1000000 ))e-3" >> "$out/timings.csv"
run step-convergence
# One step of the 256 x 256 backward-Euler target as it is (its own stiffness and dt).
t0=$(date +%s%N)
echo "paper: hooke step-convergence target_backward_euler_256 --as-is ..."
"$hooke" step-convergence "$here/../problems/scenes/target_backward_euler_256.toml" --as-is \
  --out "$out/step-convergence-256"
echo "step-convergence 256,$(( ($(date +%s%N) - t0) / 1000000 ))e-3" >> "$out/timings.csv"
run energy
# The implicit step's linear backends as the cloth grows (1e4 to 1e6 springs; 6e6 with --full).
run scaling --methods implicit-pcg,implicit-pcg-nodal,implicit-petsc,implicit-petsc-gamg --threads 2
# The SPH methods on a 3D cube of water, 1e4 to 1e6 particles, 1 and 2 threads.
t0=$(date +%s%N)
echo "paper: hooke scaling --methods wcsph,iisph ..."
"$hooke" scaling --methods wcsph,iisph --out "$out/scaling-sph"
echo "scaling sph,$(( ($(date +%s%N) - t0) / 1000000 ))e-3" >> "$out/timings.csv"

# One cloth across 1 and 2 MPI processes (one thread each): symplectic Euler and backward Euler on
# PETSc, 1e4 to 1e6 springs (6e6 with --full), with the partition's ghost traffic; pcg-nodal on
# one process (1 and 2 threads) as the reference.
t0=$(date +%s%N)
echo "paper: hooke scaling --mpi ..."
"$hooke" scaling --mpi --methods symplectic-euler,implicit-petsc,implicit-pcg-nodal "${size[@]}" \
  --out "$out/scaling-mpi"
echo "scaling mpi,$(( ($(date +%s%N) - t0) / 1000000 ))e-3" >> "$out/timings.csv"

{
  echo "| property | value |"
  echo "|---|---|"
  echo "| CPU | $(lscpu | sed -n 's/^Model name: *//p' | head -1), $(nproc) cores |"
  echo "| memory | $(free -g | awk '/^Mem:/{print $2}') GiB |"
  echo "| OS | Debian $(cat /etc/debian_version 2>/dev/null || echo unknown), kernel $(uname -r) |"
  echo "| compiler | $(c++ --version | head -1) (Release build) |"
  echo "| BLAS | OpenBLAS, OPENBLAS_CORETYPE=${OPENBLAS_CORETYPE:-unset}, OPENBLAS_NUM_THREADS=${OPENBLAS_NUM_THREADS:-unset} |"
  echo "| hooke | $("$hooke" --version), commit $(git -C "$here" rev-parse --short HEAD 2>/dev/null || echo unknown) |"
  echo "| size | ${size[*]:-default (small)} |"
  echo "| load average when done | $(cut -d' ' -f1-3 /proc/loadavg) (the machine is shared: wall times are noisy) |"
  echo "| date | $(date -u '+%Y-%m-%d %H:%M UTC') |"
} > "$out/machine.md"

/usr/bin/python3 -B "$here/assemble.py" "$here/paper.md" "$out"
pandoc "$out/paper.md" --from markdown --to html5 --standalone --self-contained --toc \
  --resource-path="$out" --metadata title="hooke: stability, cost and resolution of stiff mass-spring integrators" \
  --css "$here/paper.css" -o "$out/paper.html"
echo "paper: wrote $out/paper.html (sources: $out/paper.md, figures and CSV in $out/*/)"
