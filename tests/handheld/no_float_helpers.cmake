# Fails when a handheld library calls a floating-point helper of the ARM EABI
# run-time (__aeabi_f*, __aeabi_d*, __aeabi_*2f, __aeabi_*2d ...) or of
# libgcc's soft-float (__addsf3, __muldf3, __fixsfsi ...): core and raster use
# no floating point at all, so no such symbol may be undefined in them.
# usage: cmake -DNM=<nm> -DLIBS="a.a;b.a" -P no_float_helpers.cmake
execute_process(COMMAND ${NM} -u ${LIBS} OUTPUT_VARIABLE undefined RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${NM} failed on ${LIBS}")
endif()
string(REGEX MATCHALL "__aeabi_[a-z0-9]*[fd][a-z0-9]*|__[a-z]+[sdt]f[0-9]|__fix[a-z]*[sd]f[a-z]*|__float[a-z]*" found "${undefined}")
list(FILTER found EXCLUDE REGEX "__aeabi_(uidiv|idiv|uidivmod|idivmod|ldivmod|uldivmod|lmul|llsl|llsr|lasr|memcpy|memset|memclr|memmove)[0-9]*")
if(found)
  list(REMOVE_DUPLICATES found)
  message(FATAL_ERROR "floating-point helpers called from ${LIBS}: ${found}")
endif()
message(STATUS "no floating-point helpers in ${LIBS}")
