# Runs `hooke run` on one malformed scene and checks that it is refused as bad input.
#   cmake -DHOOKE=<hooke binary> -DSCENE=<malformed .toml> -DOUT=<scratch dir> -P run_malformed.cmake
#
# The scene's first line is `# expect: KEY`: the dotted key (mesh.springs[1], time.dt) or, for TOML
# syntax and OBJ content errors, the line (line 4) the message must name. Optional lines right
# after it:
#   # expect-file: SUFFIX   the message names a file ending in SUFFIX (an OBJ mesh) instead of
#                           the scene itself
#   # expect-text: TEXT     the message also contains TEXT (e.g. the memory a mesh would need);
#                           several such lines: it contains each
#   # env: NAME=VALUE       run hooke with this environment variable set (e.g. a memory budget)
#   # set: SECTION.KEY=VALUE  run hooke with --set SECTION.KEY=VALUE (several lines: one each)
# With -DMAKE_HUGE=ON the scene is first created: a two-line header followed by zero bytes up to
# 65 MiB (a sparse file), to check the scene-size limit without shipping a huge file.
# Passes only if hooke exits with exactly 2 (no crash, no signal, no timeout), stderr starts with
# "error: FILE: KEY: " (for a "line N" key, "error: FILE: line N, column C: " also matches) and the
# output directory was never created.
cmake_policy(SET CMP0007 NEW)  # the header's blank lines are list elements: keep them, quietly
foreach(var HOOKE SCENE OUT)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "run_malformed.cmake: pass -D${var}=...")
  endif()
endforeach()

if(MAKE_HUGE)
  get_filename_component(_dir "${SCENE}" DIRECTORY)
  file(MAKE_DIRECTORY "${_dir}")
  file(WRITE "${SCENE}" "# expect: file\n# expect-text: MiB\n")
  execute_process(COMMAND truncate -s 65M "${SCENE}" RESULT_VARIABLE _rc)
  if(NOT _rc EQUAL 0)
    message(FATAL_ERROR "could not create the huge scene ${SCENE}")
  endif()
endif()

file(STRINGS "${SCENE}" header LIMIT_COUNT 12)
list(GET header 0 first)
if(NOT first MATCHES "^# expect: (.+)$")
  message(FATAL_ERROR "${SCENE}: the first line must be '# expect: KEY', got '${first}'")
endif()
string(STRIP "${CMAKE_MATCH_1}" key)
set(expect_file "${SCENE}")
set(expect_texts "")
set(file_is_suffix FALSE)
set(env_prefix "")
set(sets "")
foreach(line IN LISTS header)
  if(line MATCHES "^# expect-file: (.+)$")
    string(STRIP "${CMAKE_MATCH_1}" expect_file)
    set(file_is_suffix TRUE)
  elseif(line MATCHES "^# expect-text: (.+)$")
    string(STRIP "${CMAKE_MATCH_1}" _text)
    list(APPEND expect_texts "${_text}")
  elseif(line MATCHES "^# env: ([A-Za-z_0-9]+=.*)$")
    string(STRIP "${CMAKE_MATCH_1}" _assign)
    set(env_prefix "${CMAKE_COMMAND}" -E env "${_assign}")
  elseif(line MATCHES "^# set: ([A-Za-z_0-9.]+=.*)$")
    string(STRIP "${CMAKE_MATCH_1}" _assign)
    list(APPEND sets --set "${_assign}")
  endif()
endforeach()

file(REMOVE_RECURSE "${OUT}")
execute_process(
  COMMAND ${env_prefix} "${HOOKE}" run "${SCENE}" --out "${OUT}" --no-progress ${sets}
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 60)

set(report "\n--- exit: ${rc}\n--- stderr:\n${err}\n--- stdout:\n${out}")
if(NOT rc STREQUAL "2")
  # A crash shows up here as a signal name ("Segmentation fault", "Child aborted").
  message(FATAL_ERROR "expected exit code 2 (bad input), got '${rc}'${report}")
endif()
string(FIND "${err}" "error: " at)
if(NOT at EQUAL 0)
  message(FATAL_ERROR "stderr must start with 'error: '${report}")
endif()

# The first line of stderr must be "error: FILE: KEY: reason".
string(REGEX REPLACE "\n.*" "" message_line "${err}")
set(candidates "${key}: ")
if(key MATCHES "^line [0-9]+$")
  list(APPEND candidates "${key}, column ")
endif()
set(found FALSE)
foreach(tail IN LISTS candidates)
  if(file_is_suffix)
    string(FIND "${message_line}" "${expect_file}: ${tail}" at)
    if(at GREATER 0)
      set(found TRUE)
    endif()
  else()
    string(FIND "${message_line}" "error: ${expect_file}: ${tail}" at)
    if(at EQUAL 0)
      set(found TRUE)
    endif()
  endif()
endforeach()
if(NOT found)
  message(FATAL_ERROR "expected 'error: ${expect_file}: ${key}: ...' "
                      "on the first line of stderr${report}")
endif()
foreach(expect_text IN LISTS expect_texts)
  string(FIND "${message_line}" "${expect_text}" at)
  if(at LESS 0)
    message(FATAL_ERROR "expected the message to contain '${expect_text}'${report}")
  endif()
endforeach()
if(EXISTS "${OUT}")
  message(FATAL_ERROR "a refused scene must not create its output directory ${OUT}${report}")
endif()
message(STATUS "refused as expected: ${message_line}")
