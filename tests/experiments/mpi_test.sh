#!/usr/bin/env bash
# One simulation across MPI processes (issue 17), end to end, one CASE per CTest test:
#   mpi_test.sh CASE HOOKE MPIRUN SCENES_DIR OUT
# Every process runs one OpenMP thread; mpirun may oversubscribe the two cores and run as root.
# Cases:
#   explicit   The explicit steppers on 1, 2 and 3 processes give the serial run's final.csv byte
#              for byte and its log.csv (every column but wall_time), and its frames as .pvtu
#              files of one .vtu piece per process: every explicit method (forward and
#              symplectic Euler, midpoint, trapezoid, RK4, dopri5 and bs32 at fixed steps) on the
#              16 x 16 hanging cloth, RK4 on the cloth pulled by a scripted corner
#              and on the cloth falling on two spheres (colliders).
#   failures   Bad input and refused scenes exit 2 with the serial run's message, printed once; a
#              mesh above the memory budget is refused with half the serial budget on 2 processes
#              (each builds the whole scene, sharing this machine's memory); a
#              diverging run and a run whose state turns non-finite (with one halving) exit 3 at the
#              serial run's step with its message, keeping the same log.csv.
#   implicit   Backward Euler with the PETSc backend at linear_tolerance = 1e-12, 10 steps of a
#              large h (0.02 s) on the 16 x 16 cloth: 2 processes within 1e-8 m of serial
#              pcg-nodal (pcg without CHOLMOD) and of 1 process; implicit midpoint, BDF2 and
#              Newton-iterated backward Euler (10 steps of 5 ms) on 2 processes within 1e-8 m
#              of serial petsc; a
#              one-process linear solver across processes is refused at integrator.linear_solver.
#   scaling    hooke scaling --mpi on an 18 x 18 cloth: rows for 1 and 2 processes, and the
#              communication model read off the partition as a strip of two rows (flexion springs
#              reach two) on each side: 72 ghosts, 2 messages, 1728 bytes per exchange; PETSc's own
#              log of a 2-process run of the 16 x 16 cloth (PETSC_OPTIONS=-log_view) counts 2
#              messages per step and 2 x 32 x 24 bytes, as the model says.
#   resume     A 2-process run stopped by --stop-after (exit 130, one checkpoint.bin of the whole
#              system) resumes on 2 processes and on 1 to the uninterrupted serial run's final.csv.
#              BDF2 and backward Euler on PETSc stopped on 2 processes (each writing its piece of
#              the checkpoint: local state and stepper history) resume on 2 to the uninterrupted
#              2-process run's final.csv within 1e-6 m, saying they are not bit for bit (the
#              PETSc hierarchy is rebuilt), and on 1 process (which holds no piece) saying they
#              restart their history, and then farther from it than 1e-6 m; with a damaged piece,
#              the resume says so and continues from the whole state.
#   signals    SIGTERM to one process of a 2-process run, or to mpirun: every process stops at
#              one step with one checkpoint, says so once, and the run resumes from it; one
#              process signalled exits 143, mpirun signalled exits 1.
set -uo pipefail
CASE=${1:?case} HOOKE=${2:?hooke binary} MPIRUN=${3:?mpirun} SCENES=${4:?scenes dir} OUT=${5:?scratch dir}
rm -rf "$OUT" && mkdir -p "$OUT"
export OMP_NUM_THREADS=1 OMPI_MCA_rmaps_base_oversubscribe=1
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
checks=0
fail() { echo "FAIL: $*" >&2; exit 1; }
ok() { checks=$((checks + 1)); }
# run P DIR ARGS...: hooke on P processes (0: no mpirun), stdout/stderr in DIR.out/.err; sets rc.
run() {
  local p=$1 dir=$2
  shift 2
  if [ "$p" = 0 ]; then
    "$HOOKE" "$@" --out "$dir" --no-progress > "$dir.out" 2> "$dir.err"
  else
    "$MPIRUN" -q -n "$p" "$HOOKE" "$@" --out "$dir" --no-progress > "$dir.out" 2> "$dir.err"
  fi
  rc=$?
}
expect_rc() {  # expect_rc WANT WHAT
  [ "$rc" = "$1" ] || fail "$2: expected exit $1, got $rc (stderr: $(tail -c 600 "$3.err"))"
  ok
}
strip_wall() { awk -F, 'BEGIN { OFS = "," } { $9 = ""; print }' "$1/log.csv"; }
same_run() {  # same_run SERIAL_DIR MPI_DIR: final.csv byte for byte, log.csv but wall_time
  cmp -s "$1/final.csv" "$2/final.csv" || fail "final.csv differs: $1 vs $2"
  diff -q <(strip_wall "$1") <(strip_wall "$2") > /dev/null || fail "log.csv differs: $1 vs $2"
  ok
}
# close_x DIR_A DIR_B TOL: every position of final.csv within TOL metres, over all particles.
close_x() {
  awk -F, -v tol="$3" 'NR == FNR { if (FNR > 1) for (c = 2; c <= 4; c++) a[FNR, c] = $c; next }
    FNR > 1 { for (c = 2; c <= 4; c++) { d = a[FNR, c] - $c; if (d < 0) d = -d; if (d > m) m = d } n++ }
    END { printf "max |x difference| %.3g m over %d particles\n", m, n; exit !(n > 0 && m <= tol) }' \
    "$1/final.csv" "$2/final.csv" || fail "final.csv of $1 and $2 differ by more than $3 m"
  ok
}
# same_frames SERIAL_DIR MPI_DIR P: the MPI run wrote the serial run's frames, at the same times,
# each as a .pvtu listing its P .vtu pieces (the pieces' contents: VtuWriter.* in CTest).
same_frames() {
  diff -q <(sed 's/\.vtk"/.pvtu"/' "$1/frames.pvd") "$2/frames.pvd" > /dev/null ||
    fail "frames.pvd: $(diff <(sed 's/\.vtk"/.pvtu"/' "$1/frames.pvd") "$2/frames.pvd")"
  local frame pieces
  for frame in "$2"/frames/*.pvtu; do
    pieces=$(grep -o 'Source="[^"]*"' "$frame" | sed 's/Source="//; s/"$//')
    [ "$(echo "$pieces" | wc -l)" = "$3" ] || fail "$frame lists $(echo "$pieces" | wc -l) pieces, not $3"
    for piece in $pieces; do
      [ -s "$2/frames/$piece" ] || fail "$frame: no piece $piece"
    done
  done
  ok
}
# The messages of a serial and an MPI run, with their output folders' names made equal.
same_err() {
  diff <(sed "s|$1|DIR|g" "$1.err") <(sed "s|$2|DIR|g" "$2.err") > /dev/null ||
    fail "stderr differs: $1.err vs $2.err: $(diff <(sed "s|$1|DIR|g" "$1.err") <(sed "s|$2|DIR|g" "$2.err"))"
  ok
}

case "$CASE" in
explicit)
  cloth=$SCENES/hanging_cloth_16.toml
  for m in forward-euler symplectic-euler midpoint trapezoid rk4 dopri5 bs32; do
    args=(run "$cloth" --set integrator.method=$m --set time.duration=0.05)
    run 0 "$OUT/$m" "${args[@]}" && expect_rc 0 "serial $m" "$OUT/$m"
    for p in 1 2 3; do
      run $p "$OUT/$m.$p" "${args[@]}"
      expect_rc 0 "$m on $p processes" "$OUT/$m.$p"
      same_run "$OUT/$m" "$OUT/$m.$p"
      [ "$p" = 1 ] || same_frames "$OUT/$m" "$OUT/$m.$p" $p
    done
  done
  for scene in cloth_pulled_by_corner cloth_on_two_spheres cloth_dihedral strand_cantilever; do
    # 100 rk4 steps each; the strand's stiff bending (EI 2e-3 N m^2 at 5 mm spacing) needs rk4
    # below 4e-5 s, so its 100 steps cover a tenth of the time.
    dt=2e-4 duration=0.02
    [ "$scene" = strand_cantilever ] && dt=2e-5 duration=0.002
    args=(run "$SCENES/$scene.toml" --set integrator.method=rk4 --set time.dt=$dt
          --set time.duration=$duration)
    run 0 "$OUT/$scene" "${args[@]}"
    expect_rc 0 "serial $scene" "$OUT/$scene"
    run 2 "$OUT/$scene.2" "${args[@]}"
    expect_rc 0 "$scene on 2 processes" "$OUT/$scene.2"
    same_run "$OUT/$scene" "$OUT/$scene.2"
  done
  ;;
failures)
  cloth=$SCENES/hanging_cloth_16.toml
  # Bad input: the serial message, once.
  run 0 "$OUT/bad" run "$cloth" --set integrator.method=no-such-method
  expect_rc 2 "bad method, serial" "$OUT/bad"
  run 2 "$OUT/bad.2" run "$cloth" --set integrator.method=no-such-method
  expect_rc 2 "bad method, 2 processes" "$OUT/bad.2"
  same_err "$OUT/bad" "$OUT/bad.2"
  [ ! -e "$OUT/bad.2" ] || fail "bad input left $OUT/bad.2 on disk"
  ok
  # What does not run across processes yet is refused up front, naming the key and the way out.
  run 2 "$OUT/vbd.2" run "$cloth" --set integrator.method=vbd
  expect_rc 2 "vbd on 2 processes" "$OUT/vbd.2"
  grep -q "^error: $cloth: integrator.method: 'vbd' does not run across MPI processes yet" \
    "$OUT/vbd.2.err" || fail "vbd: $(cat "$OUT/vbd.2.err")"
  [ "$(grep -c '^error:' "$OUT/vbd.2.err")" = 1 ] || fail "the error was printed more than once"
  ok
  run 2 "$OUT/fluid.2" run "$SCENES/dam_break_2d.toml"
  expect_rc 2 "a fluid on 2 processes" "$OUT/fluid.2"
  # The memory budget is per process: each builds the whole scene, so the processes sharing this
  # machine share its memory (unless HOOKE_MAX_MEMORY_GIB sets the budget).
  big=(run "$cloth" --set mesh.nx=40000 --set mesh.ny=40000)
  run 0 "$OUT/big" "${big[@]}"
  expect_rc 2 "a mesh above the budget, serial" "$OUT/big"
  run 2 "$OUT/big.2" "${big[@]}"
  expect_rc 2 "a mesh above the budget, 2 processes" "$OUT/big.2"
  grep -q "divided among the 2 processes of this MPI run on this machine" "$OUT/big.2.err" ||
    fail "2 processes: $(cat "$OUT/big.2.err")"
  budget() { grep -o 'memory budget of [0-9.e+]* GiB' "$1" | awk '{ print $4 }'; }
  awk -v one="$(budget "$OUT/big.err")" -v two="$(budget "$OUT/big.2.err")" \
    'BEGIN { exit !(one > 0 && two > 0 && (two == 64 || (one / two > 1.98 && one / two < 2.02))) }' ||
    fail "the budget of 2 processes is not half of one's: $(budget "$OUT/big.err") and $(budget "$OUT/big.2.err") GiB"
  ok
  # Divergence: the same step, message and log.
  args=(run "$SCENES/two_particle.toml" --set integrator.method=rk4 --set time.dt=0.05
        --set time.duration=5)
  run 0 "$OUT/diverge" "${args[@]}"
  expect_rc 3 "diverging, serial" "$OUT/diverge"
  run 2 "$OUT/diverge.2" "${args[@]}"
  expect_rc 3 "diverging, 2 processes" "$OUT/diverge.2"
  same_err "$OUT/diverge" "$OUT/diverge.2"
  diff -q <(strip_wall "$OUT/diverge") <(strip_wall "$OUT/diverge.2") > /dev/null ||
    fail "diverging: log.csv differs"
  grep -q "^failed" "$OUT/diverge.2/status.txt" || fail "diverging: status.txt does not say failed"
  ok
  # A non-finite state (no log row to catch the energy first), retried once as two halves.
  args=(run "$cloth" --set integrator.method=forward-euler --set time.dt=0.05
        --set time.duration=20 --set output.log_every=1000 --set run.max_step_halvings=1)
  run 0 "$OUT/nan" "${args[@]}"
  expect_rc 3 "non-finite, serial" "$OUT/nan"
  grep -q "state became non-finite" "$OUT/nan.err" || fail "non-finite: $(cat "$OUT/nan.err")"
  run 2 "$OUT/nan.2" "${args[@]}"
  expect_rc 3 "non-finite, 2 processes" "$OUT/nan.2"
  same_err "$OUT/nan" "$OUT/nan.2"
  ;;
implicit)
  cloth=$SCENES/hanging_cloth_16.toml
  base=(run "$cloth" --set time.dt=0.02 --set time.duration=0.2 --set integrator.linear_tolerance=1e-12)
  serial=pcg-nodal
  "$HOOKE" run --help | grep -q "pcg-nodal" || serial=pcg  # a build without CHOLMOD
  run 0 "$OUT/serial" "${base[@]}" --set integrator.method=implicit --set integrator.linear_solver=$serial
  expect_rc 0 "serial $serial" "$OUT/serial"
  for p in 1 2; do
    run $p "$OUT/petsc.$p" "${base[@]}" --set integrator.method=implicit --set integrator.linear_solver=petsc
    expect_rc 0 "petsc on $p processes" "$OUT/petsc.$p"
    close_x "$OUT/serial" "$OUT/petsc.$p" 1e-8
  done
  close_x "$OUT/petsc.1" "$OUT/petsc.2" 1e-8
  # Newton (damper df/dx left out of A: it contracts linearly, so with a smaller h).
  for m in implicit-midpoint bdf2 "implicit --set integrator.newton_iterations=10
           --set integrator.tolerance=1e-8 --set time.dt=0.005 --set time.duration=0.05"; do
    name=${m%% *}.$(echo "$m" | wc -w)
    # shellcheck disable=SC2086 # $m holds a method and its options
    run 0 "$OUT/$name" "${base[@]}" --set integrator.method=$m --set integrator.linear_solver=petsc
    expect_rc 0 "serial $m" "$OUT/$name"
    # shellcheck disable=SC2086
    run 2 "$OUT/$name.2" "${base[@]}" --set integrator.method=$m --set integrator.linear_solver=petsc
    expect_rc 0 "$m on 2 processes" "$OUT/$name.2"
    close_x "$OUT/$name" "$OUT/$name.2" 1e-8
  done
  run 2 "$OUT/cg.2" "${base[@]}" --set integrator.method=implicit --set integrator.linear_solver=pcg
  expect_rc 2 "pcg across processes" "$OUT/cg.2"
  grep -q "integrator.linear_solver: linear solver 'pcg' solves on one process only" "$OUT/cg.2.err" ||
    fail "pcg across processes: $(cat "$OUT/cg.2.err")"
  ok
  ;;
scaling)
  "$HOOKE" scaling --mpi --springs 2000 --methods symplectic-euler,implicit-petsc --steps 1 \
    --no-plot --out "$OUT/study" > "$OUT/study.out" 2> "$OUT/study.err"
  rc=$?
  expect_rc 0 "hooke scaling --mpi" "$OUT/study"
  csv=$OUT/study/scaling.csv
  for m in symplectic-euler implicit-petsc; do
    grep -q "^$m x1,1,1766,324,.*,1,0,0,0,\"ok\"$" "$csv" || fail "no 1-process row of $m: $(cat "$csv")"
    grep -q "^$m x2,1,1766,324,.*,2,72,2,1728,\"ok\"$" "$csv" || fail "no 2-process row of $m: $(cat "$csv")"
    ok
  done
  # PETSc's log: 1000 exchanges (steps) of 2 messages, 2 x 32 ghosts x 24 bytes each (the
  # run's other messages, a few at set-up, then weigh about 1%: the log gives shares in whole
  # percent).
  PETSC_OPTIONS=-log_view "$MPIRUN" -q -n 2 "$HOOKE" run "$SCENES/hanging_cloth_16.toml" \
    --set integrator.method=symplectic-euler --set time.duration=0.5 --set output.every=0 \
    --out "$OUT/logged" --no-progress > "$OUT/logged.out" 2> "$OUT/logged.err"
  rc=$?
  expect_rc 0 "a run with -log_view" "$OUT/logged"
  awk -v want=$((1000 * 2 * 32 * 24)) '
    /^MPI Msg Len \(bytes\):/ { total = $8 }
    $1 == "VecScatterBegin" { calls = $2; messages = $8; share = $14 }
    END { got = total * share / 100; d = got - want; if (d < 0) d = -d
          printf "PETSc: %d scatters, %g messages, %.0f bytes (model %d)\n", calls, messages, got, want
          exit !(calls == 1000 && messages == 2000 && d <= 0.01 * want) }' "$OUT/logged.out" ||
    fail "PETSc's log disagrees with the model: $(grep -E 'MPI Msg|VecScatterBegin' "$OUT/logged.out")"
  ok
  ;;
resume)
  args=(run "$SCENES/hanging_cloth_16.toml" --set integrator.method=rk4 --set time.duration=0.1)
  run 0 "$OUT/whole" "${args[@]}"
  expect_rc 0 "uninterrupted serial run" "$OUT/whole"
  for p in 2 1; do
    run 2 "$OUT/stopped.$p" "${args[@]}" --stop-after 77
    expect_rc 130 "--stop-after on 2 processes" "$OUT/stopped.$p"
    [ -f "$OUT/stopped.$p/checkpoint.bin" ] && [ ! -e "$OUT/stopped.$p/final.csv" ] ||
      fail "the stopped run left no checkpoint, or a final.csv"
    ok
    if [ "$p" = 1 ]; then
      "$HOOKE" resume "$OUT/stopped.$p" --no-progress > /dev/null 2> "$OUT/resume.$p.err"
    else
      "$MPIRUN" -q -n "$p" "$HOOKE" resume "$OUT/stopped.$p" --no-progress > /dev/null \
        2> "$OUT/resume.$p.err"
    fi
    rc=$?
    expect_rc 0 "resume on $p processes" "$OUT/resume.$p"
    same_run "$OUT/whole" "$OUT/stopped.$p"
    ! ls "$OUT/stopped.$p"/checkpoint* > /dev/null 2>&1 || fail "a finished run left a checkpoint"
    ok
  done
  # Implicit steps keep a history (BDF2: the previous state; every Krylov solve: its warm start).
  # Each process writes it in its piece of the checkpoint, and a resume on as many processes
  # takes it back. (Without the pieces BDF2 would restart with a backward Euler step, the solves
  # from a zero guess.) The PETSc backend's multigrid hierarchy is not in the pieces: the resumed
  # run builds a new one where the uninterrupted run may still reuse an older one
  # (PetscSolver::exact_resume() is false), so the resume says it is not bit for bit and the two
  # runs must agree to the solves' tolerance: linear_tolerance 1e-8 of the velocity change over
  # 10 steps of a 1 m cloth is far below 1e-6 m, while a lost history is not (BDF2 resumed on one
  # process, which restarts it with a backward Euler step: 1.8e-3 m, measured).
  for m in bdf2 implicit; do
    args=(run "$SCENES/hanging_cloth_16.toml" --set integrator.method="$m" --set time.dt=0.02
          --set time.duration=0.2 --set integrator.linear_solver=petsc
          --set integrator.linear_tolerance=1e-8)
    run 2 "$OUT/$m.whole" "${args[@]}"
    expect_rc 0 "uninterrupted $m on 2 processes" "$OUT/$m.whole"
    run 2 "$OUT/$m.stopped" "${args[@]}" --stop-after 4
    expect_rc 130 "$m --stop-after on 2 processes" "$OUT/$m.stopped"
    for r in 0 1; do
      [ -s "$OUT/$m.stopped/checkpoint.4.$r-of-2.bin" ] || fail "no checkpoint piece of process $r: $(ls "$OUT/$m.stopped")"
    done
    ok
    "$MPIRUN" -q -n 2 "$HOOKE" resume "$OUT/$m.stopped" --no-progress > /dev/null 2> "$OUT/$m.resume.err"
    rc=$?
    expect_rc 0 "$m resumed on 2 processes" "$OUT/$m.resume"
    grep -q "not bit for bit" "$OUT/$m.resume.err" ||
      fail "$m on petsc resumed without saying it is not bit for bit: $(cat "$OUT/$m.resume.err")"
    close_x "$OUT/$m.whole" "$OUT/$m.stopped" 1e-6
  done
  # On another process count the pieces do not fit: BDF2 resumed on one process continues from
  # the whole state and restarts its history with a backward Euler step, says so, and ends
  # measurably elsewhere (the 1e-6 m above does separate a kept history from a lost one).
  args=(run "$SCENES/hanging_cloth_16.toml" --set integrator.method=bdf2 --set time.dt=0.02
        --set time.duration=0.2 --set integrator.linear_solver=petsc
        --set integrator.linear_tolerance=1e-8)
  run 2 "$OUT/bdf2.one" "${args[@]}" --stop-after 4
  expect_rc 130 "bdf2 --stop-after on 2 processes" "$OUT/bdf2.one"
  "$HOOKE" resume "$OUT/bdf2.one" --no-progress > /dev/null 2> "$OUT/bdf2.one.resume.err"
  rc=$?
  expect_rc 0 "bdf2 resumed on 1 process" "$OUT/bdf2.one.resume"
  grep -q "keeps an internal history that this checkpoint does not hold: it restarts at step 4 as a new stepper would" \
    "$OUT/bdf2.one.resume.err" || fail "bdf2 resumed on 1 process: $(cat "$OUT/bdf2.one.resume.err")"
  ok
  far=$(awk -F, 'NR == FNR { if (FNR > 1) for (c = 2; c <= 4; c++) a[FNR, c] = $c; next }
    FNR > 1 { for (c = 2; c <= 4; c++) { d = a[FNR, c] - $c; if (d < 0) d = -d; if (d > m) m = d } }
    END { print (m > 1e-6) ? "yes" : "no " m }' "$OUT/bdf2.whole/final.csv" "$OUT/bdf2.one/final.csv")
  [ "$far" = yes ] ||
    fail "bdf2 resumed without its history ends within 1e-6 m ($far): the check above cannot tell"
  ok
  # A damaged piece is not used: the run resumes from checkpoint.bin's whole state and says why.
  run 2 "$OUT/damaged" "${args[@]}" --stop-after 4
  expect_rc 130 "--stop-after on 2 processes" "$OUT/damaged"
  printf '\001' | dd of="$OUT/damaged/checkpoint.4.1-of-2.bin" bs=1 seek=300 conv=notrunc 2> /dev/null
  "$MPIRUN" -q -n 2 "$HOOKE" resume "$OUT/damaged" --no-progress > /dev/null 2> "$OUT/damaged.resume.err"
  rc=$?
  expect_rc 0 "resume with a damaged piece" "$OUT/damaged.resume"
  grep -q "checkpoint.4.1-of-2.bin: checkpoint: corrupt (checksum mismatch); resuming from the whole state" \
    "$OUT/damaged.resume.err" || fail "damaged piece: $(cat "$OUT/damaged.resume.err")"
  ok
  ;;
signals)
  # A signal reaches one process of a run, or mpirun: every process stops at the same step with
  # one complete checkpoint (the pieces of that step, then checkpoint.bin), says where, and the
  # run resumes from it. A process signalled alone exits 143 as a serial run would, and mpirun
  # passes that code on; mpirun signalled itself forwards the signal and exits 1.
  args=(run "$SCENES/hanging_cloth_16.toml" --set integrator.method=rk4 --set time.dt=1e-4
        --set time.duration=1000 --set output.vtk=false --set output.png=false
        --set output.log_every=1)
  # started DIR: waits (at most 120 s) until the run in DIR has logged 20 steps.
  started() {
    local i
    for i in $(seq 1200); do
      [ -f "$1/log.csv" ] && [ "$(wc -l < "$1/log.csv")" -gt 20 ] && return 0
      sleep 0.1
    done
    fail "the run in $1 logged no 20 steps in 120 s: $(tail -c 600 "$1.err")"
  }
  stopped_at() {  # stopped_at DIR WHAT SIGNAL: one checkpoint of one step, status stopped, message
    [ -f "$1/checkpoint.bin" ] && [ ! -e "$1/final.csv" ] || fail "$2: no checkpoint, or a final.csv"
    grep -q "^stopped" "$1/status.txt" || fail "$2: status.txt says $(cat "$1/status.txt")"
    grep -q "interrupted by $3 at step" "$1.err" || fail "$2: stderr: $(tail -c 600 "$1.err")"
    [ "$(grep -c "interrupted by $3 at step" "$1.err")" = 1 ] ||
      fail "$2: the interruption reported more than once: $(cat "$1.err")"
    ok
  }
  # SIGTERM to the process of rank 1 only.
  "$MPIRUN" -q -n 2 "$HOOKE" "${args[@]}" --out "$OUT/rank" --no-progress > "$OUT/rank.out" \
    2> "$OUT/rank.err" &
  launcher=$!
  started "$OUT/rank"
  ranks=$(pgrep -f -- "--out $OUT/rank --no-progress" | grep -vx "$launcher" | sort -n)
  [ "$(echo "$ranks" | wc -l)" = 2 ] || fail "found processes '$ranks' of the run, not two"
  kill -TERM "$(echo "$ranks" | tail -1)"
  wait "$launcher"
  rc=$?
  expect_rc 143 "one process signalled" "$OUT/rank"
  stopped_at "$OUT/rank" "one process signalled" SIGTERM
  step=$(grep -o "interrupted by SIGTERM at step [0-9]*" "$OUT/rank.err" | grep -o "[0-9]*$")
  "$MPIRUN" -q -n 2 "$HOOKE" resume "$OUT/rank" --no-progress --stop-after $((step + 5)) \
    > /dev/null 2> "$OUT/rank.resume.err"
  rc=$?
  expect_rc 130 "resume after a signal, stopped again 5 steps later" "$OUT/rank.resume"
  [ "$(tail -1 "$OUT/rank/log.csv" | cut -d, -f1)" = $((step + 5)) ] ||
    fail "the resumed run did not continue from step $step: $(tail -2 "$OUT/rank/log.csv")"
  ok
  # SIGTERM to mpirun.
  "$MPIRUN" -q -n 2 "$HOOKE" "${args[@]}" --out "$OUT/launcher" --no-progress > "$OUT/launcher.out" \
    2> "$OUT/launcher.err" &
  launcher=$!
  started "$OUT/launcher"
  kill -TERM "$launcher"
  wait "$launcher"
  rc=$?
  expect_rc 1 "mpirun signalled" "$OUT/launcher"
  stopped_at "$OUT/launcher" "mpirun signalled" SIGTERM
  ;;
*)
  fail "unknown case $CASE"
  ;;
esac
echo "mpi $CASE: $checks checks passed"
