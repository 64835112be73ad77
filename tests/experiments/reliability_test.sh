#!/usr/bin/env bash
# End-to-end reliability checks of the hooke command, one CASE per CTest test:
#   reliability_test.sh CASE HOOKE SCENES_DIR OUT
# Cases:
#   stop_resume  For rk4, implicit on pcg (warm start), bdf2 (multistep history),
#                implicit-midpoint on cholmod, and the 2D dam break by wcsph, iisph and dfsph
#                (warm starts): a run stopped by --stop-after (exit 130, checkpoint
#                written, no final.csv) and resumed (twice for bdf2: stop, resume with another
#                --stop-after, resume) gives a final.csv identical byte for byte to an
#                uninterrupted run, the same log.csv (every column but wall_time: no step missing
#                or duplicated) and the same frames.pvd.
#   signals      A 4000-step run interrupted by a real SIGINT, by SIGTERM, and killed by SIGKILL
#                after its first periodic checkpoint (run.checkpoint_every): exit 130 / 143 / kill,
#                then `hooke resume` finishes it with a final.csv identical byte for byte to an
#                uninterrupted run, and the same log.csv.
#   determinism  The same scene twice with the same thread count: identical final.csv (a 129 x 129
#                cloth, so the OpenMP paths run). OMP_NUM_THREADS=1 against 2: identical for pcg;
#                for cholmod (OpenBLAS threads change the order of floating-point sums) within
#                1e-12 relative to the largest value (measured: 1e-19 for x, 3e-16 for v after 5
#                steps); see docs/long-runs.md "Determinism".
#   faults       Numerical failures: pcg limited to 1 iteration stops with exit 3, naming the step,
#                time, method, backend and residual, keeping log.csv (run.allow_not_converged =
#                true accepts such steps and counts them); pcg limited to 20 iterations fails at h
#                but with run.max_step_halvings = 4 retries with h/2 .. h/16, says so, and
#                finishes; cholmod and cg on an indefinite A (compressed spring, no clamp) and
#                cvode with max_steps = 5 stop with exit 3 and their own numbers.
#   resume_errors  `hooke resume` on a finished run, on a directory without checkpoint, and on a
#                corrupt checkpoint: exit 2 with "error: FILE: checkpoint: reason".
set -uo pipefail
CASE=${1:?case} HOOKE=${2:?hooke binary} SCENES=${3:?scenes dir} OUT=${4:?scratch dir}
rm -rf "$OUT" && mkdir -p "$OUT"
checks=0
fail() { echo "FAIL: $*" >&2; exit 1; }
ok() { checks=$((checks + 1)); }
expect_rc() {  # expect_rc WANT GOT WHAT
  [ "$2" = "$1" ] || fail "$3: expected exit $1, got $2 (stderr: $(tail -c 600 "$OUT/last.err" 2>/dev/null))"
  ok
}
same_final() { cmp -s "$1/final.csv" "$2/final.csv" || fail "final.csv differs: $1 vs $2"; ok; }
# log.csv without the wall_time column (9): every other column must match row for row.
strip_wall() { awk -F, 'BEGIN { OFS = "," } { $9 = ""; print }' "$1/log.csv"; }
same_log() {
  diff -q <(strip_wall "$1") <(strip_wall "$2") > /dev/null || fail "log.csv differs: $1 vs $2"
  local steps dups
  steps=$(awk -F, 'NR > 1 { print $1 }' "$2/log.csv" | wc -l)
  dups=$(awk -F, 'NR > 1 { print $1 }' "$2/log.csv" | sort | uniq -d | wc -l)
  [ "$steps" -gt 2 ] && [ "$dups" -eq 0 ] || fail "$2/log.csv: $steps rows, $dups duplicated steps"
  ok
}
# Largest |a - b| over x..vz relative to the largest |a| must be <= tol.
close_final() {
  awk -F, -v tol="$3" 'NR == FNR { if (FNR > 1) for (c = 2; c <= 7; c++) a[FNR, c] = $c; next }
    FNR > 1 { for (c = 2; c <= 7; c++) { d = a[FNR, c] - $c; if (d < 0) d = -d; if (d > dmax) dmax = d;
              m = a[FNR, c] < 0 ? -a[FNR, c] : a[FNR, c]; if (m > amax) amax = m } n++ }
    END { printf "max |difference| %.3g, relative %.3g over %d particles\n", dmax, dmax / amax, n;
          exit !(n > 0 && dmax <= tol * amax) }' "$1/final.csv" "$2/final.csv" ||
    fail "final.csv of $1 and $2 differ by more than $3 relative"
  ok
}
run() {  # run OUTDIR ARGS...: hooke run with stderr kept in $OUT/last.err; sets rc
  local dir=$1
  shift
  "$HOOKE" "$@" --no-progress > "$OUT/last.out" 2> "$OUT/last.err"
  rc=$?
}

case "$CASE" in
stop_resume)
  # stopped NAME SCENE ARGS...: an uninterrupted run against one stopped after step 13 (and for
  # bdf2 again after 29) and resumed.
  stopped() {
    local name=$1 scene=$2
    shift 2
    run x run "$scene" --out "$OUT/$name-ref" "$@"
    expect_rc 0 $rc "$name: uninterrupted run"
    run x run "$scene" --out "$OUT/$name" "$@" --stop-after 13
    expect_rc 130 $rc "$name: --stop-after 13"
    [ -f "$OUT/$name/checkpoint.bin" ] && [ ! -e "$OUT/$name/final.csv" ] ||
      fail "$name: a stopped run must leave checkpoint.bin and no final.csv"
    ok
    if [ "${name%%-*}" = bdf2 ]; then
      run x resume "$OUT/$name" --stop-after 29
      expect_rc 130 $rc "$name: resume --stop-after 29"
    fi
    run x resume "$OUT/$name"
    expect_rc 0 $rc "$name: resume"
    [ ! -e "$OUT/$name/checkpoint.bin" ] || fail "$name: a finished run must remove its checkpoint"
    same_final "$OUT/$name-ref" "$OUT/$name"
    same_log "$OUT/$name-ref" "$OUT/$name"
    cmp -s "$OUT/$name-ref/frames.pvd" "$OUT/$name/frames.pvd" || fail "$name: frames.pvd differs"
    [ "$(ls "$OUT/$name/frames" | wc -l)" = "$(ls "$OUT/$name-ref/frames" | wc -l)" ] ||
      fail "$name: frame count differs"
    ok
  }
  cloth="$SCENES/hanging_cloth_16.toml"
  common=(--set time.duration=0.1 --set output.every=7 --set output.png=false)
  for cfg in "rk4" "implicit pcg" "bdf2 pcg" "implicit-midpoint cholmod"; do
    set -- $cfg
    args=("${common[@]}" --set integrator.method="$1")
    [ $# -gt 1 ] && args+=(--set integrator.linear_solver="$2" --set time.dt=0.002)
    stopped "${cfg// /-}" "$cloth" "${args[@]}"
  done
  # The fluid methods, with CFL substeps: IISPH's checkpoint carries its warm start (the last
  # pressures; DFSPH's, both solves'), and the neighbour lists depend on the positions alone.
  for m in wcsph iisph dfsph; do
    stopped "$m" "$SCENES/dam_break_2d.toml" --set time.duration=0.03 --set output.every=7 \
      --set output.png=false --set integrator.method=$m
  done
  ;;
signals)
  scene="$SCENES/hanging_cloth_16.toml"
  args=(--set time.duration=2 --set output.vtk=false --set output.png=false)
  run x run "$scene" --out "$OUT/ref" "${args[@]}"
  expect_rc 0 $rc "uninterrupted run"
  for sig in INT TERM KILL; do
    dir="$OUT/$sig"
    extra=()
    [ $sig = KILL ] && extra=(--set run.checkpoint_every=300)
    "$HOOKE" run "$scene" --out "$dir" "${args[@]}" "${extra[@]}" --no-progress \
      > "$OUT/last.out" 2> "$OUT/last.err" &
    pid=$!
    # Signal once the run is under way (for KILL: once its first periodic checkpoint exists).
    for _ in $(seq 1 200); do
      if [ $sig = KILL ]; then [ -f "$dir/checkpoint.bin" ] && break
      else [ -f "$dir/log.csv" ] && [ "$(wc -l < "$dir/log.csv")" -gt 20 ] && break; fi
      sleep 0.02
    done
    kill -$sig $pid
    wait $pid
    rc=$?
    case $sig in INT) want=130 ;; TERM) want=143 ;; KILL) want=137 ;; esac
    expect_rc $want $rc "run stopped by SIG$sig"
    [ -f "$dir/checkpoint.bin" ] && [ ! -e "$dir/final.csv" ] ||
      fail "SIG$sig: expected checkpoint.bin and no final.csv (did the run end before the signal?)"
    ok
    run x resume "$dir"
    expect_rc 0 $rc "resume after SIG$sig"
    grep -q "resuming" "$OUT/last.err" || fail "resume did not say where it resumed"
    same_final "$OUT/ref" "$dir"
    same_log "$OUT/ref" "$dir"
  done
  ;;
determinism)
  big=(--set mesh.nx=129 --set mesh.ny=129 --set integrator.method=implicit --set time.dt=0.002
       --set time.duration=0.004 --set output.vtk=false --set output.png=false)
  for ls in pcg cholmod; do
    for t in 1 2; do
      OMP_NUM_THREADS=$t run x run "$SCENES/hanging_cloth.toml" --out "$OUT/$ls-t$t" "${big[@]}" \
        --set integrator.linear_solver=$ls
      expect_rc 0 $rc "$ls with $t threads"
    done
    if [ $ls = pcg ]; then same_final "$OUT/$ls-t1" "$OUT/$ls-t2"; else close_final "$OUT/$ls-t1" "$OUT/$ls-t2" 1e-12; fi
  done
  OMP_NUM_THREADS=2 run x run "$SCENES/hanging_cloth.toml" --out "$OUT/pcg-t2-again" "${big[@]}" \
    --set integrator.linear_solver=pcg
  expect_rc 0 $rc "pcg with 2 threads again"
  same_final "$OUT/pcg-t2" "$OUT/pcg-t2-again"
  same_log "$OUT/pcg-t2" "$OUT/pcg-t2-again"
  ;;
faults)
  cloth="$SCENES/hanging_cloth_16.toml"
  run x run "$cloth" --out "$OUT/pcg1" --set integrator.method=implicit --set time.dt=0.01 \
    --set integrator.linear_solver=pcg --set integrator.max_linear_iterations=1
  expect_rc 3 $rc "pcg with 1 iteration"
  for text in "step 2 failed" "t = 0.01" "h = 0.01" "method implicit, linear solver pcg" \
              "not-converged" "relative residual" "after 1 iterations" "kept:"; do
    grep -qF "$text" "$OUT/last.err" || fail "pcg failure message lacks '$text': $(cat "$OUT/last.err")"
    ok
  done
  [ -f "$OUT/pcg1/log.csv" ] && [ ! -e "$OUT/pcg1/final.csv" ] || fail "pcg failure: log.csv kept, no final.csv"
  ok
  run x run "$cloth" --out "$OUT/pcg1-allowed" --set integrator.method=implicit --set time.dt=0.01 \
    --set integrator.linear_solver=pcg --set integrator.max_linear_iterations=1 \
    --set run.allow_not_converged=true --set time.duration=0.05
  expect_rc 0 $rc "pcg with 1 iteration, allow_not_converged"
  grep -q "steps did not converge" "$OUT/last.err" || fail "allow_not_converged must count the steps"
  ok
  # pcg capped at 20 iterations misses 1e-8 at h = 0.02 but reaches it at h/8 (A nearer M).
  cap=(--set integrator.method=implicit --set integrator.linear_solver=pcg --set time.dt=0.02
       --set time.duration=0.06 --set integrator.max_linear_iterations=20)
  run x run "$cloth" --out "$OUT/pcg20-halved" "${cap[@]}" --set run.max_step_halvings=3
  expect_rc 3 $rc "pcg 20 iterations, 3 halvings (h/8 is not enough everywhere)"
  grep -qF "h = 0.0025" "$OUT/last.err" || fail "the failure must name the substep h: $(tail -3 "$OUT/last.err")"
  ok
  run x run "$cloth" --out "$OUT/pcg20-halved" "${cap[@]}" --set run.max_step_halvings=4
  expect_rc 0 $rc "pcg 20 iterations, 4 halvings"
  grep -qF "retrying as two steps of h/2 = 0.01" "$OUT/last.err" &&
    grep -qF "2 of 3 steps were retried with a smaller h" "$OUT/last.err" ||
    fail "halving must be reported: $(tail -3 "$OUT/last.err")"
  ok
  # A compressed spring without the clamp makes A indefinite: Cholesky breaks down, so does CG.
  cat > "$OUT/indefinite.toml" <<'EOF'
[mesh]
type = "particles"
positions = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 0.8, 0.0]]
pins = [0]
springs = [[0, 1, 1e4, 10.0], [1, 2, 1e4], [0, 2, 1e4]]

[integrator]
method = "implicit"
clamp_compressed = false

[time]
dt = 0.01
duration = 0.05
EOF
  for ls in cholmod cg; do
    run x run "$OUT/indefinite.toml" --out "$OUT/indefinite-$ls" --set integrator.linear_solver=$ls
    expect_rc 3 $rc "$ls on an indefinite A"
    grep -qF "step 1 failed (t = 0, h = 0.01, method implicit, linear solver $ls" "$OUT/last.err" &&
      grep -qF "broke-down" "$OUT/last.err" && grep -qF "not positive definite" "$OUT/last.err" ||
      fail "$ls breakdown message: $(cat "$OUT/last.err")"
    ok
  done
  # CVODE allowed 5 internal steps per output step gives up (too much work).
  "$HOOKE" run --help | grep -q "cvode" || { echo "faults: $checks checks passed (no cvode in this build)"; exit 0; }
  run x run "$cloth" --out "$OUT/cvode" --set integrator.method=cvode --set integrator.max_steps=5 \
    --set time.dt=0.01
  expect_rc 3 $rc "cvode with max_steps = 5"
  grep -qF "method cvode (klu)" "$OUT/last.err" && grep -qF "CV_TOO_MUCH_WORK" "$OUT/last.err" ||
    fail "cvode failure message: $(cat "$OUT/last.err")"
  ok
  ;;
resume_errors)
  scene="$SCENES/two_particle.toml"
  run x run "$scene" --out "$OUT/done" --set time.duration=0.01
  expect_rc 0 $rc "short run"
  run x resume "$OUT/done"
  expect_rc 2 $rc "resume of a finished run"
  grep -q "^error: $OUT/done/checkpoint.bin: checkpoint: does not exist" "$OUT/last.err" || fail "message: $(cat "$OUT/last.err")"
  ok
  run x run "$scene" --out "$OUT/corrupt" --set time.duration=0.01 --stop-after 3
  expect_rc 130 $rc "stopped run"
  printf 'X' | dd of="$OUT/corrupt/checkpoint.bin" bs=1 seek=40 conv=notrunc status=none
  run x resume "$OUT/corrupt"
  expect_rc 2 $rc "resume of a corrupt checkpoint"
  grep -q "checkpoint: corrupt" "$OUT/last.err" || fail "message: $(cat "$OUT/last.err")"
  ok
  head -c 30 "$OUT/done/log.csv" > "$OUT/corrupt/checkpoint.bin"
  run x resume "$OUT/corrupt"
  expect_rc 2 $rc "resume of a foreign file"
  grep -q "not a hooke checkpoint" "$OUT/last.err" || fail "message: $(cat "$OUT/last.err")"
  ok
  run x resume "$OUT/no-such-dir"
  expect_rc 2 $rc "resume of a missing directory"
  ;;
*)
  fail "unknown case $CASE"
  ;;
esac
echo "$CASE: $checks checks passed"
