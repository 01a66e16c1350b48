# Runs CMD (a ;-list) and checks its exit code is RC and that its stderr
# matches STDERR (a regular expression, optional). With LIMIT_KB, the
# command runs under that address-space limit (ulimit -v), as on a small host.
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
message(STATUS "exit ${rc}; stderr: ${err}")
