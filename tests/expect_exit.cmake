# Runs CMD (arguments separated by | or ;) and checks its exit code is RC and that its stderr and
# stdout match STDERR and STDOUT (regular expressions, optional). With LIMIT_KB, the
# command runs under that address-space limit (ulimit -v), as on a small host.
string(REPLACE "|" ";" CMD "${CMD}")  # "|" separates arguments where ";" would split a CTest argument
if(DEFINED LIMIT_KB)
  list(JOIN CMD " " line)
  execute_process(COMMAND sh -c "ulimit -v ${LIMIT_KB} && exec ${line}" RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
else()
  execute_process(COMMAND ${CMD} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
endif()
if(NOT rc STREQUAL "${RC}")
  message(FATAL_ERROR "exit ${rc}, expected ${RC}: ${CMD}\nstdout: ${out}\nstderr: ${err}")
endif()
if(DEFINED STDERR AND NOT err MATCHES "${STDERR}")
  message(FATAL_ERROR "stderr does not match '${STDERR}': ${CMD}\nstderr: ${err}")
endif()
if(DEFINED STDOUT AND NOT out MATCHES "${STDOUT}")
  message(FATAL_ERROR "stdout does not match '${STDOUT}': ${CMD}\nstdout: ${out}")
endif()
message(STATUS "exit ${rc}; stderr: ${err}")
