#!/usr/bin/env bash
# Question: does every implicit method run stably with every linear backend on a scene, and at
# what cost? Runs `hooke run SCENE` once per (method, linear backend) pair with the same extra
# overrides, and tabulates exit status, wall time, linear iterations (mean and max per step),
# steps whose linear solve or Newton iteration missed its tolerance, and final total energy.
#
# Usage: experiments/drivers/method_matrix.sh SCENE OUT_DIR [--set section.key=value]...
#   e.g. experiments/drivers/method_matrix.sh hanging_cloth out/matrix \
#          --set time.dt=0.016666666666666666 --set springs.structural_stiffness=1e4
# Environment: HOOKE (path of the hooke binary, default build/bin/hooke), METHODS and BACKENDS
# (space-separated lists; default every implicit method and every linear backend of this build).
# Writes OUT_DIR/<method>-<backend>/ (each run's output) and OUT_DIR/matrix.md, OUT_DIR/matrix.csv.
set -uo pipefail
scene=${1:?usage: method_matrix.sh SCENE OUT_DIR [--set k=v]...}
out=${2:?usage: method_matrix.sh SCENE OUT_DIR [--set k=v]...}
shift 2
hooke=${HOOKE:-build/bin/hooke}
methods=${METHODS:-"implicit implicit-midpoint bdf2"}
backends=${BACKENDS:-$("$hooke" run --help 2>/dev/null | sed -n 's/^Linear solvers: //p' | tr -d ',')}
[ -n "$backends" ] || { echo "method_matrix: cannot list linear backends from $hooke" >&2; exit 1; }
mkdir -p "$out"
csv="$out/matrix.csv"
md="$out/matrix.md"
echo "method,backend,exit,wall_s,steps,mean_lin_iters,max_lin_iters,not_converged_steps,final_total_energy" > "$csv"
{
  echo "| method | backend | exit | wall (s) | steps | mean lin. iters | max lin. iters | steps not converged | final energy (J) |"
  echo "|---|---|---|---|---|---|---|---|---|"
} > "$md"
for m in $methods; do
  for b in $backends; do
    dir="$out/$m-$b"
    start=$(date +%s.%N)
    "$hooke" run "$scene" --no-progress --force --out "$dir" --set integrator.method="$m" \
      --set integrator.linear_solver="$b" --set run.allow_not_converged=true "$@" > "$dir.stdout" 2> "$dir.stderr"
    code=$?
    wall=$(awk -v a="$(date +%s.%N)" -v b="$start" 'BEGIN {printf "%.3f", a - b}')
    nc=$(sed -n 's/.* \([0-9]*\) of [0-9]* steps did not converge.*/\1/p' "$dir.stderr")
    stats=$(awk -F, 'NR>1 && $1>0 {n++; s+=$7; if ($7>mx) mx=$7; e=$5; last=$1}
                     END {printf "%d,%.1f,%d,%.6g", last, n ? s/n : 0, mx, e}' "$dir/log.csv")
    IFS=, read -r steps mean mx energy <<< "$stats"
    echo "$m,$b,$code,$wall,$steps,$mean,$mx,${nc:-0},$energy" >> "$csv"
    echo "| $m | $b | $code | $(printf %.1f "$wall") | $steps | $mean | $mx | ${nc:-0} | $energy |" >> "$md"
    echo "$m $b: exit $code, $(printf %.1f "$wall") s" >&2
  done
done
cat "$md"
