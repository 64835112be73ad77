# End-to-end checks of the hooke command, one CASE per CTest test:
#   cmake -DCASE=<case> -DHOOKE=<hooke binary> -DSCENES_DIR=<problems/scenes> -DOUT=<scratch dir>
#         [-DSCENE=<scene file>] -P cli_test.cmake
# Cases:
#   run         runs SCENE for a short time (time.duration=0.02) and checks exit 0 and the files it
#               writes (scene.toml, log.csv, final.csv; final.png and frames/ for mass-spring
#               scenes); then runs the written scene.toml again and requires byte-identical
#               final.csv and an unchanged resolved scene.
#   diverge     two_particle with rk4 at dt = 0.05 (h omega = 7, far above rk4's 2.83): exit 3, the
#               message names the step, log.csv is kept, final.csv is not written.
#   diverge_ode decay with rk4 at dt = 10 (|R(-10)| = 291 per step): the state overflows, exit 3.
#   info        `hooke info hanging_cloth` exits 0 and describes the 32 x 32 cloth, with the OpenMP
#               spin count hooke sets (or the user's).
#   scenes      `hooke scenes` lists every shipped scene with its one-line description.
#   bad_input   missing scene file, malformed --set and unknown subcommand: exit 2 with a message.
#   stability   `hooke stability` at a tiny size (two_particle, two methods, one k): stability.csv has
#               its documented header and one row per method with a bracketed boundary; the plot
#               script writes stability_two_particle.png.
#   workprecision  `hooke workprecision` on the chain with three methods: workprecision.csv and
#               reference.csv have their headers, rk4's smallest step has a finite error; the PNG.
#   resolution  `hooke resolution` at n = 4, 6: one row per variant and size with a finite sag;
#               the cantilevers at 9 and 17 along, the shell sheet's sag near its beam's.
#   energy      `hooke energy` at 50 periods: its two CSVs, symplectic Euler bounded, backward
#               Euler dissipating, and the figure.
#   adaptive    error-controlled dopri5: log columns, frames at their times, the end line, a
#               resume that ends on the same bits, and the refusals of the error-control keys.
#   final_picture  final.png by matplotlib (axes, colour bar, colliders) and, without the plot
#               script, by the built-in renderer with a warning.
foreach(var CASE HOOKE SCENES_DIR OUT)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "cli_test.cmake: pass -D${var}=...")
  endif()
endforeach()
# `hooke info NAME` and `hooke scenes` look here first: test this tree, not an installed copy.
set(ENV{HOOKE_SCENES_DIR} "${SCENES_DIR}")

# Runs hooke with the given arguments; sets rc, out, err and a report for failure messages.
macro(hooke_exec)
  execute_process(COMMAND "${HOOKE}" ${ARGN}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 100)
  string(REPLACE ";" " " _args "${ARGN}")
  set(report "\n--- hooke ${_args}\n--- exit: ${rc}\n--- stderr:\n${err}\n--- stdout:\n${out}")
endmacro()

function(expect_rc want)
  if(NOT rc STREQUAL "${want}")
    message(FATAL_ERROR "expected exit code ${want}, got '${rc}'${report}")
  endif()
endfunction()

function(expect_contains text needle what)
  string(FIND "${text}" "${needle}" at)
  if(at LESS 0)
    message(FATAL_ERROR "expected ${what} to contain '${needle}'${report}")
  endif()
endfunction()

function(expect_file path)
  if(NOT EXISTS "${path}" OR IS_DIRECTORY "${path}")
    message(FATAL_ERROR "expected the file ${path}${report}")
  endif()
  file(SIZE "${path}" size)
  if(size EQUAL 0)
    message(FATAL_ERROR "${path} is empty${report}")
  endif()
endfunction()

# Number of lines of a text file.
function(count_lines path var)
  file(STRINGS "${path}" lines)
  list(LENGTH lines n)
  set(${var} ${n} PARENT_SCOPE)
endfunction()

# What a run that stopped with exit 3 keeps: its log.csv with at least the row of step 0, and no
# final.csv (which only a finished run writes).
function(expect_failed_run_kept_its_log)
  expect_file("${OUT}/log.csv")
  count_lines("${OUT}/log.csv" n)
  if(n LESS 2)
    message(FATAL_ERROR "log.csv was not kept: ${n} lines${report}")
  endif()
  if(EXISTS "${OUT}/final.csv")
    message(FATAL_ERROR "a failed run must not write final.csv${report}")
  endif()
endfunction()

# The resolved scene without the lines that name where it was written (header comment, output.dir).
function(resolved_body path var)
  file(READ "${path}" text)
  string(REGEX REPLACE "^#[^\n]*\n" "" text "${text}")
  string(REGEX REPLACE "\ndir = [^\n]*" "" text "${text}")
  set(${var} "${text}" PARENT_SCOPE)
endfunction()

# A CSV file with this exact header line and `lines` lines in all.
function(expect_csv path header lines)
  expect_file("${path}")
  file(STRINGS "${path}" content)
  list(GET content 0 first)
  if(NOT first STREQUAL "${header}")
    message(FATAL_ERROR "${path}: header '${first}', expected '${header}'${report}")
  endif()
  list(LENGTH content n)
  if(NOT n EQUAL ${lines})
    message(FATAL_ERROR "${path}: ${n} lines, expected ${lines}${report}")
  endif()
endfunction()

file(REMOVE_RECURSE "${OUT}")

if(CASE STREQUAL "run")
  file(STRINGS "${SCENE}" sections REGEX "^\\[ode\\]")
  set(is_ode FALSE)
  if(sections)
    set(is_ode TRUE)
  endif()
  hooke_exec(run "${SCENE}" --out "${OUT}/first" --no-progress --set time.duration=0.02)
  expect_rc(0)
  foreach(f scene.toml log.csv final.csv)
    expect_file("${OUT}/first/${f}")
  endforeach()
  count_lines("${OUT}/first/log.csv" n)
  if(n LESS 3)
    message(FATAL_ERROR "log.csv has ${n} lines; expected a header and at least 2 rows${report}")
  endif()
  if(NOT is_ode)
    file(STRINGS "${OUT}/first/final.csv" header LIMIT_COUNT 1)
    if(NOT header STREQUAL "id,x,y,z,vx,vy,vz")
      message(FATAL_ERROR "unexpected final.csv header '${header}'${report}")
    endif()
    expect_file("${OUT}/first/final.png")
    file(READ "${OUT}/first/final.png" magic LIMIT 8 HEX)
    if(NOT magic STREQUAL "89504e470d0a1a0a")
      message(FATAL_ERROR "final.png does not start with the PNG signature (${magic})${report}")
    endif()
    file(GLOB frames "${OUT}/first/frames/*.vtk")
    list(LENGTH frames nframes)
    if(nframes LESS 2)
      message(FATAL_ERROR "expected at least the first and last frame in frames/, found ${nframes}${report}")
    endif()
  endif()

  # The written scene.toml, run from its own directory, reproduces the run exactly.
  hooke_exec(run "${OUT}/first/scene.toml" --out "${OUT}/second" --no-progress)
  expect_rc(0)
  file(READ "${OUT}/first/final.csv" a)
  file(READ "${OUT}/second/final.csv" b)
  if(NOT a STREQUAL b)
    message(FATAL_ERROR "rerunning ${OUT}/first/scene.toml gave a different final.csv "
                        "(compare with ${OUT}/second/final.csv)${report}")
  endif()
  resolved_body("${OUT}/first/scene.toml" a)
  resolved_body("${OUT}/second/scene.toml" b)
  if(NOT a STREQUAL b)
    message(FATAL_ERROR "resolving the resolved scene changed it: compare ${OUT}/first/scene.toml "
                        "and ${OUT}/second/scene.toml${report}")
  endif()

elseif(CASE STREQUAL "diverge")
  hooke_exec(run "${SCENE}" --out "${OUT}" --no-progress --set integrator.method=rk4
             --set time.dt=0.05 --set time.duration=5)
  expect_rc(3)
  if(NOT err MATCHES "^error: [^\n]*diverged at step [0-9]+ \\(t = ")
    message(FATAL_ERROR "expected 'error: FILE: diverged at step N (t = ...' on stderr${report}")
  endif()
  expect_contains("${err}" "log.csv" "stderr")
  expect_file("${OUT}/scene.toml")
  expect_failed_run_kept_its_log()

elseif(CASE STREQUAL "fluid_explode")
  # WCSPH without CFL substeps at 25 times its CFL step: the fluid explodes, and the run stops
  # with exit 3 naming the limit it crossed, keeping its log.
  hooke_exec(run "${SCENE}" --out "${OUT}" --no-progress --set integrator.courant=0
             --set time.dt=0.004 --set time.duration=0.5)
  expect_rc(3)
  if(NOT err MATCHES "^error: [^\n]*step [0-9]+ failed \\(t = [^\n]*method wcsph[^\n]*fatal: (CFL|density): ")
    message(FATAL_ERROR "expected 'error: FILE: step N failed (t = ..., method wcsph ...): fatal: "
                        "CFL: ...' or '... density: ...' on stderr${report}")
  endif()
  expect_contains("${err}" "integrator.courant" "stderr")
  expect_failed_run_kept_its_log()
  file(STRINGS "${OUT}/log.csv" header LIMIT_COUNT 1)
  if(NOT header MATCHES ",max_density_error,mean_density_error,pressure_iterations,substeps,front,lost$")
    message(FATAL_ERROR "a fluid log.csv has the fluid columns, lost last; header: ${header}")
  endif()

elseif(CASE STREQUAL "fluid_info")
  hooke_exec(info "${SCENE}")
  expect_rc(0)
  expect_contains("${out}" "fluid:      800 particles (2D, spacing 0.0125 m" "stdout")
  expect_contains("${out}" "boundary:   " "stdout")
  expect_contains("${out}" "CFL step:   " "stdout")

elseif(CASE STREQUAL "diverge_ode")
  hooke_exec(run "${SCENE}" --out "${OUT}" --no-progress --set integrator.method=rk4
             --set time.dt=10 --set time.duration=5000)
  expect_rc(3)
  if(NOT err MATCHES "^error: [^\n]*diverged at step [0-9]+ \\(t = ")
    message(FATAL_ERROR "expected 'error: FILE: diverged at step N (t = ...' on stderr${report}")
  endif()
  expect_file("${OUT}/log.csv")
  if(EXISTS "${OUT}/final.csv")
    message(FATAL_ERROR "a diverged run must not write final.csv${report}")
  endif()

elseif(CASE STREQUAL "info")
  # libgomp's and OpenBLAS's wait policies: hooke sets GOMP_SPINCOUNT and OPENBLAS_THREAD_TIMEOUT
  # (solver/parallel/thread_policy.hpp) unless the user chose them, and says which it runs with.
  unset(ENV{OMP_WAIT_POLICY})
  set(ENV{GOMP_SPINCOUNT} 123)
  set(ENV{OPENBLAS_THREAD_TIMEOUT} 7)
  hooke_exec(info hanging_cloth)
  expect_rc(0)
  expect_contains("${out}" "GOMP_SPINCOUNT=123)" "stdout (the user's spin count)")
  expect_contains("${out}" "OPENBLAS_THREAD_TIMEOUT=7\n" "stdout (the user's OpenBLAS timeout)")
  unset(ENV{GOMP_SPINCOUNT})
  hooke_exec(info hanging_cloth)
  expect_rc(0)
  expect_contains("${out}" "GOMP_SPINCOUNT=10000)" "stdout (hooke's spin count)")
  expect_contains("${out}" "OPENBLAS_THREAD_TIMEOUT=7\n" "stdout (the user's OpenBLAS timeout)")
  unset(ENV{OPENBLAS_THREAD_TIMEOUT})
  hooke_exec(info hanging_cloth)
  expect_rc(0)
  expect_contains("${out}" "OPENBLAS_THREAD_TIMEOUT=20\n" "stdout (hooke's OpenBLAS timeout)")
  expect_contains("${out}" "particles:  1024 (2 pinned)" "stdout")
  expect_contains("${out}" "omega_max:" "stdout")
  expect_contains("${out}" "rk4" "stdout")
  # What a run will write: 10000 steps with a frame every 500 (21 frames), against what it writes.
  expect_contains("${out}" "output:     21 VTK frames of about " "stdout")
  if(NOT out MATCHES "VTK frames of about ([0-9.]+) MiB each")
    message(FATAL_ERROR "no frame size in hooke info${report}")
  endif()
  set(estimate "${CMAKE_MATCH_1}")
  hooke_exec(run hanging_cloth --set time.duration=0.0002 --out "${OUT}/run" --no-progress)
  expect_rc(0)
  file(SIZE "${OUT}/run/frames/frame_00000000.vtk" bytes)
  math(EXPR lo "${bytes} * 95 / 100")
  math(EXPR hi "${bytes} * 105 / 100")
  # estimate is in MiB with 6 significant digits; compare in bytes.
  string(REGEX REPLACE "^0\\." "" digits "${estimate}")
  if(NOT estimate MATCHES "^0\\.[0-9]+$")
    message(FATAL_ERROR "frame estimate '${estimate}' MiB: expected below 1 MiB${report}")
  endif()
  string(LENGTH "${digits}" places)
  math(EXPR scaled "${digits} * 1048576")
  set(denominator 1)
  foreach(k RANGE 1 ${places})
    math(EXPR denominator "${denominator} * 10")
  endforeach()
  math(EXPR est_bytes "${scaled} / ${denominator}")
  if(est_bytes LESS lo OR est_bytes GREATER hi)
    message(FATAL_ERROR "hooke info estimates ${est_bytes} bytes a frame; a frame has ${bytes}${report}")
  endif()
  # A scene over the memory budget cannot run, but info still describes it (exit 0).
  hooke_exec(info hanging_cloth --set mesh.nx=100000 --set mesh.ny=100000)
  expect_rc(0)
  expect_contains("${out}" "particles:  1e+10" "stdout")
  expect_contains("${out}" "over the memory budget, so a run is refused" "stdout")
  expect_contains("${out}" "VTK frames of about " "stdout")
  hooke_exec(info "${SCENES_DIR}/decay.toml")
  expect_rc(0)
  expect_contains("${out}" "ODE" "stdout")

elseif(CASE STREQUAL "crosscheck")
  # A short cross-check against the CVODE reference writes its table; rk4 at a small step must
  # be close to the reference (the Markdown row has a finite RMS error, not "-").
  hooke_exec(crosscheck hanging_cloth_16 --methods rk4,implicit --samples 4
             --set time.duration=0.01 --out "${OUT}")
  expect_rc(0)
  expect_file("${OUT}/crosscheck.md")
  expect_file("${OUT}/crosscheck.csv")
  expect_contains("${out}" "| rk4 | 0.0005 |" "stdout")
  expect_contains("${out}" "| implicit | 0.0005 |" "stdout")
  # The energy column is the error against the reference's energy at T, not E(T) - E(0): CVODE
  # itself, compared with its own reference, is close to 0 there.
  file(STRINGS "${OUT}/crosscheck.csv" header LIMIT_COUNT 1)
  if(NOT header MATCHES ",energy_err_final,")
    message(FATAL_ERROR "crosscheck.csv has no energy_err_final column: '${header}'${report}")
  endif()
  expect_contains("${out}" "E(T) - E_ref(T) (J)" "stdout")
  file(STRINGS "${OUT}/crosscheck.csv" rk4 REGEX "^rk4,")
  if(NOT rk4 MATCHES "^rk4,[^,]*,[^,]*,[^,]*,[^,]*,[^,]*,[^,]*,-?[0-9.]+e-(0[7-9]|[1-9][0-9]),")
    message(FATAL_ERROR "rk4's energy error against the reference is not below 1e-6 J: '${rk4}'${report}")
  endif()
  if(out MATCHES "\\| rk4 \\|[^\n]*\\| - \\|")
    message(FATAL_ERROR "rk4 has no error against the reference${report}")
  endif()
  # A misspelt method is an input error, before the reference is computed.
  hooke_exec(crosscheck hanging_cloth_16 --methods rk4,rk5 --out "${OUT}/bad")
  expect_rc(2)
  expect_contains("${err}" "--methods: unknown method 'rk5'" "stderr")
  if(err MATCHES "reference cvode")
    message(FATAL_ERROR "the reference was computed before the bad --methods was refused${report}")
  endif()

elseif(CASE STREQUAL "step_convergence")
  # The default study writes its CSV, table and plot; at k = 100 (a soft cloth) every
  # local/global variant and Newton reach the 1e-6 target (a number, not "-", in the table).
  hooke_exec(step-convergence --out "${OUT}")
  expect_rc(0)
  foreach(f step_convergence.csv step_convergence.md step_convergence.png)
    expect_file("${OUT}/${f}")
  endforeach()
  foreach(m fast-mass-spring/none fast-mass-spring/chebyshev fast-mass-spring/lbfgs newton-beta1-cholmod)
    if(NOT out MATCHES "\\| 100 \\| 0.01 \\| [^|]+ \\| ${m} \\| [0-9]+ \\|")
      message(FATAL_ERROR "${m} did not reach the target at k = 100${report}")
    endif()
  endforeach()

elseif(CASE STREQUAL "factor_over_budget")
  # The 256 x 256 target's mesh fits a 0.5 GiB budget (about 0.36 GiB) but, with pcg-cholmod, its
  # 3n x 3n CHOLMOD factor does not (about 1 GiB): refused after the symbolic analysis, before the
  # numeric factorization allocates, as an input error naming the file, the key and the estimate.
  # (The scene's own pcg-nodal factors the n x n nodal matrix, which fits.)
  set(ENV{HOOKE_MAX_MEMORY_GIB} 0.5)
  hooke_exec(run "${SCENES_DIR}/target_backward_euler_256.toml" --out "${OUT}" --no-progress
             --set time.duration=0.02 --set integrator.linear_solver=pcg-cholmod)
  unset(ENV{HOOKE_MAX_MEMORY_GIB})
  expect_rc(2)
  expect_contains("${err}" "target_backward_euler_256.toml: integrator.linear_solver: cholmod: the factorization" "stderr")
  expect_contains("${err}" "above the memory budget of 0.5 GiB" "stderr")
  # Refused at setup: the output folder is never created.
  if(EXISTS "${OUT}")
    message(FATAL_ERROR "a run refused at setup created ${OUT}${report}")
  endif()

elseif(CASE STREQUAL "scaling")
  # Two small grids, every method, 1 and 2 threads: one CSV row each, all "ok", and the plot
  # script's figure and table of fitted exponents. An unknown method is an input error.
  # 10 methods (13 with the PETSc backend) x 2 sizes x 2 thread counts, the 3 fluid methods at as
  # many particles (cubes of 13^3 and 20^3), and the header.
  set(methods symplectic-euler xpbd fast-mass-spring fast-mass-spring-jacobi vbd vbd-chebyshev
              implicit-pcg implicit-pcg-cholmod implicit-pcg-nodal implicit-cholmod)
  if(WITH_PETSC)
    list(APPEND methods implicit-petsc implicit-petsc-gamg implicit-petsc-boomeramg)
  endif()
  list(LENGTH methods n_methods)
  math(EXPR rows "4 * ${n_methods} + 12 + 1")
  hooke_exec(scaling --springs 2000,8000 --steps 1 --out "${OUT}")
  expect_rc(0)
  expect_csv("${OUT}/scaling.csv"
             "method,threads,springs,particles,steps,step_s,iterations_per_step,iteration_s,assembly_s,factor_s,solve_s,local_s,global_s,setup_s,peak_mib,factor_nnz,processes,ghosts,exchange_messages,exchange_bytes,status"
             ${rows})
  file(READ "${OUT}/scaling.csv" text)
  if(text MATCHES "failed")
    message(FATAL_ERROR "a scaling run failed${report}")
  endif()
  foreach(m IN LISTS methods)
    expect_contains("${text}" "${m},2,7846,1369," "scaling.csv")
  endforeach()
  foreach(m IN ITEMS wcsph iisph dfsph)
    expect_contains("${text}" "${m},2,0,8000," "scaling.csv")
  endforeach()
  expect_file("${OUT}/scaling.png")
  file(READ "${OUT}/scaling.md" md)
  expect_contains("${md}" "| fast-mass-spring | 2 | 2 |" "scaling.md")
  hooke_exec(scaling --springs 2000 --methods nonsense --out "${OUT}/bad")
  expect_rc(2)
  expect_contains("${err}" "--methods" "stderr")

elseif(CASE STREQUAL "demo")
  # `hooke demo`: the stiff cloth by backward Euler (runs to the end) and by symplectic Euler at the
  # same step (diverges, which is the point: exit 0), the summary line in summary.txt, the picture.
  # An --explicit method that is not explicit is an input error.
  hooke_exec(demo --out "${OUT}")
  expect_rc(0)
  file(READ "${OUT}/summary.txt" summary)
  expect_contains("${summary}" "symplectic-euler diverged at step " "summary.txt")
  expect_contains("${summary}" "x its limit h < 2 / omega_max = " "summary.txt")
  expect_contains("${summary}"
                  "backward Euler (implicit, beta = 1) on pcg-cholmod stable: 400 steps to t = 2 s"
                  "summary.txt")
  expect_contains("${out}" "demo: symplectic-euler diverged" "stdout")
  expect_file("${OUT}/demo.png")
  expect_file("${OUT}/implicit/final.csv")
  expect_file("${OUT}/explicit/log.csv")
  hooke_exec(demo --explicit implicit --out "${OUT}/bad")
  expect_rc(2)
  expect_contains("${err}" "--explicit" "stderr")

elseif(CASE STREQUAL "final_picture")
  # final.png is drawn by experiments/plot/final.py from final.vtk and scene.toml (matplotlib's
  # 7.6 x 6.2 in at 110 dpi: 836 x 682 pixels); without the script, by the built-in renderer
  # (960 x 720) with a warning. Either way the run succeeds and final.vtk is the final state.
  foreach(variant matplotlib builtin)
    if(variant STREQUAL "builtin")
      set(ENV{HOOKE_PLOT_DIR} "${OUT}/no_plot_scripts_here")
      set(want_size "000003c0000002d0")
    else()
      unset(ENV{HOOKE_PLOT_DIR})
      set(want_size "00000344000002aa")
    endif()
    hooke_exec(run cloth_on_two_spheres --set time.duration=0.05 --out "${OUT}/${variant}")
    expect_rc(0)
    expect_file("${OUT}/${variant}/final.vtk")
    expect_file("${OUT}/${variant}/final.png")
    # The PNG's IHDR: width and height, big-endian, at bytes 16..23.
    file(READ "${OUT}/${variant}/final.png" size OFFSET 16 LIMIT 8 HEX)
    if(NOT size STREQUAL want_size)
      message(FATAL_ERROR "final.png (${variant}) has IHDR size ${size}, expected ${want_size}"
                          "${report}")
    endif()
    if(variant STREQUAL "builtin")
      expect_contains("${err}" "final.png is drawn by the built-in renderer" "stderr")
    else()
      string(FIND "${err}" "warning" warned)
      if(NOT warned EQUAL -1)
        message(FATAL_ERROR "unexpected warning${report}")
      endif()
    endif()
  endforeach()

elseif(CASE STREQUAL "damper_override")
  # fast-mass-spring and xpbd refuse spring dampers; the refusal prints the --set switches that
  # take them out, and those switches run the scene. Every shipped scene with dampers (the large
  # target scenes aside), briefly.
  file(GLOB shipped "${SCENES_DIR}/*.toml")
  set(checked 0)
  foreach(scene IN LISTS shipped)
    get_filename_component(stem "${scene}" NAME_WLE)
    if(stem MATCHES "^target_")
      continue()
    endif()
    foreach(method fast-mass-spring xpbd)
      hooke_exec(run "${scene}" --set integrator.method=${method} --set time.duration=0.02
                 --out "${OUT}/${stem}" --no-progress --force)
      if(NOT err MATCHES "spring-damper")
        continue()
      endif()
      expect_rc(2)
      if(NOT err MATCHES "or run it without spring dampers: ([^\n]*)")
        message(FATAL_ERROR "${stem}, ${method}: the refusal names no --set switches${report}")
      endif()
      string(STRIP "${CMAKE_MATCH_1}" sets)
      separate_arguments(sets UNIX_COMMAND "${sets}")
      hooke_exec(run "${scene}" --set integrator.method=${method} ${sets}
                 --set time.duration=0.02 --out "${OUT}/${stem}" --no-progress --force)
      expect_rc(0)
      math(EXPR checked "${checked} + 1")
    endforeach()
  endforeach()
  if(checked LESS 4)
    message(FATAL_ERROR "only ${checked} (scene, method) refusals checked; expected at least 4")
  endif()

elseif(CASE STREQUAL "strain_limit_note")
  # A run whose strain limiting cannot keep up (xpbd on the hanging cloth with a 1% limit) ends
  # with a note naming the limit, the worst strain and the passes; with the scene's 10% limit,
  # which its springs never reach, there is no note.
  hooke_exec(run "${SCENES_DIR}/hanging_cloth.toml" --set integrator.method=xpbd
             --set springs.damping=0 --set strain_limit.max_strain=0.01 --set time.duration=0.1
             --out "${OUT}/tight" --no-progress)
  expect_rc(0)
  expect_contains("${err}" "beyond the strain limit 0.01 (worst " "stderr")
  expect_contains("${err}" "projection passes (strain_limit.passes) ran out first" "stderr")
  hooke_exec(run "${SCENES_DIR}/hanging_cloth.toml" --set integrator.method=xpbd
             --set springs.damping=0 --set time.duration=0.1 --out "${OUT}/loose" --no-progress)
  expect_rc(0)
  if(err MATCHES "strain limit")
    message(FATAL_ERROR "a note about the strain limit where no spring reached it${report}")
  endif()

elseif(CASE STREQUAL "output_interval")
  # [output] interval: frames by simulated time, the same frames whatever dt: the initial one and
  # one per 0.02 s up to 0.1 s (the last is also the final frame), at dt = 2e-4 and 1e-4. A --set
  # interval drops the file's `every` with a warning; a file with both is an input error.
  foreach(dt 2e-4 1e-4)
    hooke_exec(run "${SCENES_DIR}/hanging_cloth.toml" --set output.interval=0.02
               --set time.duration=0.1 --set time.dt=${dt} --out "${OUT}/dt${dt}" --no-progress)
    expect_rc(0)
    expect_contains("${err}" "output.every: has no effect with output.interval (from --set)"
                    "stderr")
    file(GLOB frames "${OUT}/dt${dt}/frames/*.vtk")
    list(LENGTH frames nframes)
    if(NOT nframes EQUAL 6)
      message(FATAL_ERROR "dt = ${dt}: ${nframes} frames, expected 6 (t = 0, 0.02, ..., 0.1)${report}")
    endif()
    # Frame times are the steps' nominal times, written as the shortest decimal that reads back.
    file(READ "${OUT}/dt${dt}/frames.pvd" pvd)
    expect_contains("${pvd}" "timestep=\"0.02\" " "frames.pvd")
    expect_contains("${pvd}" "timestep=\"0.1\" " "frames.pvd")
  endforeach()
  file(READ "${SCENES_DIR}/hanging_cloth.toml" text)
  string(REPLACE "[output]\nevery = 500" "[output]\nevery = 500\ninterval = 0.5" text "${text}")
  file(WRITE "${OUT}/both.toml" "${text}")
  hooke_exec(run "${OUT}/both.toml" --out "${OUT}/both" --no-progress)
  expect_rc(2)
  expect_contains("${err}" "output.every: give every (steps) or interval (seconds)" "stderr")

elseif(CASE STREQUAL "adaptive")
  # integrator.adaptive: dopri5 under error control lands on every frame time, logs the step size
  # and the cumulative accepted and rejected counts, ends with its counts in CVODE's style, and a
  # run stopped and resumed ends on the same bits as one that was not. Methods without an error
  # estimate, tolerances without adaptive, and step-counted frames are refused at their key.
  set(args "${SCENES_DIR}/hanging_cloth_16.toml" --set integrator.method=dopri5
      --set integrator.adaptive=true --set integrator.rtol=1e-6 --set integrator.atol=1e-8
      --set output.interval=0.1 --no-progress)
  hooke_exec(run ${args} --out "${OUT}/whole")
  expect_rc(0)
  expect_contains("${out}" "dopri5: steps " "stdout")
  expect_contains("${out}" ", rejected " "stdout")
  file(STRINGS "${OUT}/whole/log.csv" header LIMIT_COUNT 1)
  if(NOT header MATCHES ",wall_time,h,accepted,rejected$")
    message(FATAL_ERROR "log.csv header '${header}' lacks h,accepted,rejected${report}")
  endif()
  file(STRINGS "${OUT}/whole/log.csv" rows)
  list(GET rows -1 last)
  if(NOT last MATCHES "^[0-9]+,0.5,")
    message(FATAL_ERROR "the last log row does not end at t = 0.5: '${last}'${report}")
  endif()
  file(GLOB frames "${OUT}/whole/frames/*.vtk")
  list(LENGTH frames nframes)
  if(NOT nframes EQUAL 6)
    message(FATAL_ERROR "${nframes} frames, expected 6 (t = 0, 0.1, ..., 0.5)${report}")
  endif()
  hooke_exec(run ${args} --out "${OUT}/parts" --stop-after 100)
  expect_rc(130)
  hooke_exec(resume "${OUT}/parts" --no-progress)
  expect_rc(0)
  file(SHA256 "${OUT}/whole/final.csv" whole)
  file(SHA256 "${OUT}/parts/final.csv" parts)
  if(NOT whole STREQUAL parts)
    message(FATAL_ERROR "a stopped and resumed adaptive run ends elsewhere than a whole one${report}")
  endif()
  hooke_exec(info "${SCENES_DIR}/hanging_cloth_16.toml" --set integrator.method=dopri5
             --set integrator.adaptive=true --set integrator.rtol=1e-6)
  expect_rc(0)
  expect_contains("${out}" "error control: dopri5 with rtol = 1e-06" "hooke info")
  hooke_exec(run "${SCENES_DIR}/hanging_cloth_16.toml" --set integrator.adaptive=true
             --out "${OUT}/rk4" --no-progress)
  expect_rc(2)
  expect_contains("${err}" "integrator.adaptive: method 'rk4' makes no local error estimate" "stderr")
  hooke_exec(run "${SCENES_DIR}/hanging_cloth_16.toml" --set integrator.method=bs32
             --set integrator.rtol=1e-4 --out "${OUT}/fixed" --no-progress)
  expect_rc(2)
  expect_contains("${err}" "integrator.rtol: has no effect with adaptive = false" "stderr")
  hooke_exec(run "${SCENES_DIR}/hanging_cloth_16.toml" --set integrator.method=bs32
             --set integrator.adaptive=true --set output.every=10 --out "${OUT}/every" --no-progress)
  expect_rc(2)
  expect_contains("${err}" "output.every: counts steps" "stderr")

elseif(CASE STREQUAL "energy")
  # hooke energy at a few periods with two methods: both files with their headers, symplectic
  # Euler's error bounded and small, backward Euler's negative (it dissipates), and the figure.
  hooke_exec(energy --periods 50 --samples 20 --methods symplectic-euler,implicit-b1
             --out "${OUT}")
  expect_rc(0)
  # 703 steps (50 periods of 14.07 ms at 1 ms) sampled every 35 steps and at the end: 21 rows per
  # method.
  expect_csv("${OUT}/energy.csv" "label,method,h,t,relative_energy_error" 43)
  expect_csv("${OUT}/energy_summary.csv"
             "label,method,h,periods,final_error,max_abs_error,drift_per_period,wall_s,status" 3)
  file(STRINGS "${OUT}/energy_summary.csv" se REGEX "^symplectic-euler,")
  string(REPLACE "," ";" fields "${se}")
  list(GET fields 5 se_max)  # max_abs_error
  if(NOT se_max LESS 1e-2)
    message(FATAL_ERROR "symplectic Euler's energy error is not below 1e-2: '${se}'${report}")
  endif()
  file(STRINGS "${OUT}/energy_summary.csv" be REGEX "^implicit-b1,")
  if(NOT be MATCHES "^implicit-b1,implicit,0.001,[0-9.]+,-")
    message(FATAL_ERROR "backward Euler does not lose energy: '${be}'${report}")
  endif()
  expect_file("${OUT}/energy.png")

elseif(CASE STREQUAL "stability")
  hooke_exec(stability --cases two_particle --methods symplectic-euler,implicit-b1 --k 1e4
             --bisections 3 --out "${OUT}")
  expect_rc(0)
  expect_csv("${OUT}/stability.csv"
             "case,label,method,k,omega_max,h_theory,h_stable,h_unstable,bound,runs,wall_s,reason,parameter" 3)
  file(READ "${OUT}/stability.csv" text)
  expect_contains("${text}" "two_particle,symplectic-euler,symplectic-euler,10000,141.42" "stability.csv")
  expect_contains("${text}" ",bracketed," "stability.csv")
  expect_contains("${text}" "two_particle,implicit-b1,implicit,10000," "stability.csv")
  expect_file("${OUT}/stability_two_particle.png")
  expect_file("${OUT}/stability_two_particle.md")
  hooke_exec(stability --cases two_particle --methods symplectic-euler,implicit-b2 --out "${OUT}/bad")
  expect_rc(2)
  expect_contains("${err}" "--methods: unknown study method 'implicit-b2'" "stderr")

elseif(CASE STREQUAL "workprecision")
  # cvode at rtol 1e-11, tighter than the reference's 1e-10, agrees with it to within the
  # reference's own error: that point must be marked unresolved, not given as a value.
  hooke_exec(workprecision --cases chain --methods rk4,implicit-b1,cvode,dopri5-adaptive
             --rtols 1e-4,1e-11 --samples 2 --repeat 3 --out "${OUT}")
  expect_rc(0)
  # 4 step sizes for rk4 and implicit-b1, two tolerances for cvode and dopri5-adaptive, plus the
  # header.
  expect_csv("${OUT}/workprecision.csv"
             "case,label,method,h,rtol,wall_s,steps,rms_err_final,max_err_final,rms_err_traj,max_err_traj,status,repeats,resolved_final,resolved_traj" 13)
  # dopri5 under error control at rtol 1e-4: a resolved error within 10 x rtol x the chain's
  # size (about 1 m), counted in accepted steps.
  file(STRINGS "${OUT}/workprecision.csv" ctl REGEX "^chain,dopri5-adaptive,dopri5,[^,]*,0.0001,")
  if(NOT ctl MATCHES "^chain,dopri5-adaptive,dopri5,[^,]*,0.0001,[^,]*,[1-9][0-9]*,([0-9.]+e-0[5-9]|[0-9.]+e-[1-9][0-9]|0.000[0-9]+),.*,\"ok\",3,1,1$")
    message(FATAL_ERROR "dopri5-adaptive at rtol 1e-4 has no resolved error below 1e-3 m: '${ctl}'${report}")
  endif()
  expect_file("${OUT}/tolerance_chain.png")
  file(STRINGS "${OUT}/workprecision.csv" tight REGEX "^chain,cvode,cvode,[^,]*,1e-11,")
  if(NOT tight MATCHES ",\"ok\",3,0,0$")
    message(FATAL_ERROR "cvode at rtol 1e-11 is not marked below the reference error (3 runs): '${tight}'${report}")
  endif()
  file(STRINGS "${OUT}/workprecision.csv" coarse REGEX "^chain,implicit-b1,implicit,0.01,")
  if(NOT coarse MATCHES ",\"ok\",3,1,1$")
    message(FATAL_ERROR "backward Euler at h = 1e-2 is not a resolved error (3 runs): '${coarse}'${report}")
  endif()
  expect_csv("${OUT}/reference.csv" "case,rtol,wall_s,err_rms_final,err_rms_traj,err_max_traj,how" 2)
  file(STRINGS "${OUT}/workprecision.csv" rows REGEX "^chain,rk4,rk4,0.0001,")
  if(NOT rows MATCHES "^chain,rk4,rk4,0.0001,0,[0-9.e-]+,5000,[0-9]")
    message(FATAL_ERROR "rk4 at h = 1e-4 has no finite error: '${rows}'${report}")
  endif()
  expect_file("${OUT}/workprecision_chain.png")
  hooke_exec(workprecision --cases chain --methods rk4,nosuch --out "${OUT}/bad")
  expect_rc(2)
  expect_contains("${err}" "--methods: unknown study method 'nosuch'" "stderr")
  # The fluid case: IISPH over its four tolerances on the dam break, every run complete with a
  # front compared with Martin and Moyce, and the plot's table of them.
  hooke_exec(workprecision --cases dam_break_2d --methods iisph --repeat 1 --out "${OUT}/fluid")
  expect_rc(0)
  expect_csv("${OUT}/fluid/fluid.csv"
             "case,label,method,parameter,value,wall_s,steps,substeps,fluid_particles,particle_steps_per_s,mean_density_error,max_density_error,pressure_iterations_per_substep,front_speed,front_speed_ratio,lead_min,lead_max,status,repeats" 5)
  file(STRINGS "${OUT}/fluid/fluid.csv" fluid_rows REGEX "^dam_break_2d,iisph-")
  foreach(row IN LISTS fluid_rows)
    if(NOT row MATCHES "^dam_break_2d,iisph-[0-9.e-]+,iisph,tolerance,[0-9.e-]+,[0-9.e-]+,80,[0-9]+,800,.*,[01]\\.[0-9]+,[0-9.]+,[0-9.]+,ok,1$")
      message(FATAL_ERROR "fluid run incomplete or without a front: '${row}'${report}")
    endif()
  endforeach()
  expect_file("${OUT}/fluid/fluid_dam_break_2d.md")
  # Each run's front after every 5 ms step (80 to t = 0.4 s), after both experiments' points.
  file(STRINGS "${OUT}/fluid/fronts.csv" front_rows REGEX "^dam_break_2d,iisph-0.001,")
  list(LENGTH front_rows n_front)
  if(NOT n_front EQUAL 80)
    message(FATAL_ERROR "fronts.csv: ${n_front} points of iisph-0.001, expected 80${report}")
  endif()
  expect_contains("${front_rows}" "dam_break_2d,iisph-0.001,3.54" "fronts.csv")
  expect_file("${OUT}/fluid/front.png")
  # Naming only fluid cases leaves the mass-spring study out: no reference row.
  expect_csv("${OUT}/fluid/reference.csv" "case,rtol,wall_s,err_rms_final,err_rms_traj,err_max_traj,how" 1)

elseif(CASE STREQUAL "resolution")
  hooke_exec(resolution --n 4,6 --duration 0.5 --cantilever-n 9,17 --out "${OUT}" --no-plot)
  expect_rc(0)
  # Five cantilevers (rod; shell on both diagonals, dihedral, quadratic) at two sizes, each with
  # a finite sag.
  expect_csv("${OUT}/cantilever.csv"
             "mesh,model,diagonals,n_along,particles,sag_m,beam_m,ratio,settle_speed,wall_s" 11)
  file(STRINGS "${OUT}/cantilever.csv" rows REGEX "^sheet,shell,one-way,17,")
  if(NOT rows MATCHES "^sheet,shell,one-way,17,[0-9]+,0\\.[0-9]+,0\\.[0-9]+,(0\\.9|1\\.0)")
    message(FATAL_ERROR "the shell sheet at 17 along is not near its beam: '${rows}'${report}")
  endif()
  expect_csv("${OUT}/resolution.csv"
             "variant,n,particles,springs,k_structural,drag,period_s,sag_com_m,sag_lowest_m,settle_speed,wall_s" 7)
  file(STRINGS "${OUT}/resolution.csv" rows REGEX "^membrane,6,36,")
  if(NOT rows MATCHES "^membrane,6,36,[0-9]+,[0-9.e+-]+,[0-9.e+-]+,[^,]+,0\\.[0-9]+,")
    message(FATAL_ERROR "membrane n = 6 has no finite sag: '${rows}'${report}")
  endif()

elseif(CASE STREQUAL "check_intersections")
  # The fold (sheet_folded_onto_itself at 10 x 10) with self-contact: no frame has two triangles
  # that intersect (exit 0). Without self-contact the folded half falls through the lower one:
  # the checker names the first frame and pair (exit 1). A directory without frames: exit 2.
  set(_small --no-progress --set mesh.nx=10 --set mesh.ny=10 --set output.interval=0.1)
  hooke_exec(run "${SCENE}" --out "${OUT}/self" ${_small})
  expect_rc(0)
  hooke_exec(check-intersections "${OUT}/self")
  expect_rc(0)
  expect_contains("${out}" "no two triangles intersect" "stdout")
  hooke_exec(run "${SCENE}" --out "${OUT}/through" ${_small} --set contact.self=false
             --set contact.friction=0)
  expect_rc(0)
  hooke_exec(check-intersections "${OUT}/through")
  expect_rc(1)
  if(NOT out MATCHES "frame_[0-9]+\\.vtk \\(t = [^)]+\\): triangles [0-9]+ \\(particles ")
    message(FATAL_ERROR "expected the first frame and pair named${report}")
  endif()
  hooke_exec(check-intersections "${OUT}/no_such_dir")
  expect_rc(2)
  expect_contains("${err}" "no VTK frames" "stderr")

elseif(CASE STREQUAL "scenes")
  hooke_exec(scenes)
  expect_rc(0)
  file(GLOB shipped "${SCENES_DIR}/*.toml")
  list(LENGTH shipped nshipped)
  if(nshipped EQUAL 0)
    message(FATAL_ERROR "no shipped scenes in ${SCENES_DIR}")
  endif()
  foreach(scene IN LISTS shipped)
    get_filename_component(stem "${scene}" NAME_WLE)
    if(NOT out MATCHES "(^|\n)${stem} ")
      message(FATAL_ERROR "`hooke scenes` does not list ${stem}${report}")
    endif()
    # Its description is the scene file's first comment line.
    file(READ "${scene}" text)
    string(REGEX MATCH "^[^\n]*" first "${text}")
    string(REGEX REPLACE "^#+ *" "" first "${first}")
    expect_contains("${out}" "${first}" "stdout")
  endforeach()

elseif(CASE STREQUAL "bad_input")
  hooke_exec(run "${OUT}/no_such_scene.toml" --out "${OUT}/o" --no-progress)
  expect_rc(2)
  if(NOT err MATCHES "^error: [^\n]*no_such_scene.toml: file: ")
    message(FATAL_ERROR "expected 'error: FILE: file: ...'${report}")
  endif()
  hooke_exec(run "${SCENE}" --out "${OUT}/o" --no-progress --set time.dt)
  expect_rc(2)
  if(NOT err MATCHES "^error: <command line>: time.dt: ")
    message(FATAL_ERROR "expected 'error: <command line>: time.dt: ...'${report}")
  endif()
  hooke_exec(run "${SCENE}" --out "${OUT}/o" --no-progress --set time.dt=-1)
  expect_rc(2)
  expect_contains("${err}" ": time.dt: " "stderr")
  # A --set value over two lines would silently lose the second key; --stop-after 0 would never stop.
  hooke_exec(run "${SCENE}" --out "${OUT}/o" --no-progress "--set" "time.dt=1e-3\ntime.duration=2")
  expect_rc(2)
  expect_contains("${err}" "error: <command line>: time.dt: the value spans several lines" "stderr")
  hooke_exec(run "${SCENE}" --out "${OUT}/o" --no-progress --stop-after 0)
  expect_rc(2)
  expect_contains("${err}" "error: <command line>: --stop-after: must be a step number >= 1" "stderr")
  hooke_exec(frobnicate)
  expect_rc(2)
  hooke_exec(run)
  expect_rc(2)
  if(EXISTS "${OUT}/o")
    message(FATAL_ERROR "refused input must not create the output directory${report}")
  endif()

else()
  message(FATAL_ERROR "cli_test.cmake: unknown CASE '${CASE}'")
endif()
message(STATUS "Cli ${CASE} ok")
