# Fails when the per-point path of the client calls a run-time helper for
# division or floating point: the functions that run once per generated
# point — PointRenderer::draw_points in the affine and reciprocal projection
# modes (the bins), the tile pass's point loops (draw_tile_node_scalar and
# the NEON loop, inlined into PointRenderer::draw_tile_nodes / tile_nodes_of
# or not), PointRaster::add / split / push and the tile pass — must branch to none of
# __aeabi_idiv, __aeabi_uidiv, __aeabi_ldivmod, __aeabi_uldivmod, __aeabi_f*,
# __aeabi_d*, __aeabi_*2f, __divsi3, __addsf3 ... (per-node and init code may
# divide). The exact-division mode divides per point: with HW_DIVIDE=0
# (STIPPLE_HW_DIVIDE off, core/divide.h) it must call no helper either, with
# HW_DIVIDE=1 it must be seen calling one. As a control, the shading tables'
# set-up (init code) must be seen calling a division helper, which proves the
# calls are being found.
# usage: cmake -DOBJDUMP=<objdump> -DLIB=<libstipple_raster.a> -DHW_DIVIDE=0|1 -P per_point_helpers.cmake
execute_process(COMMAND ${OBJDUMP} -d -r -C --no-show-raw-insn ${LIB} OUTPUT_VARIABLE dis RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${OBJDUMP} failed on ${LIB}")
endif()
string(REPLACE ";" "," dis "${dis}")  # ARM assembly comments start with ';'
string(REPLACE "\n" ";" lines "${dis}")
set(helper "^(__aeabi_(u?idiv|u?idivmod|u?ldivmod|[fd][a-z0-9]+|[a-z0-9]+2[fd])|__[a-z]+[sdt]f[0-9]|__u?(div|mod)[sd]i3)")
set(current "")
set(per_point_functions 0)
set(control_found FALSE)
set(exact_divides FALSE)
if(HW_DIVIDE)
  set(per_point_modes "[01]")
else()
  set(per_point_modes "[012]")
endif()
set(violations "")
foreach(line IN LISTS lines)
  if(line MATCHES "^[0-9a-f]+ <(.*)>:$")
    set(current "${CMAKE_MATCH_1}")
    set(per_point FALSE)
    if(current MATCHES "draw_points<\\(stipple::Projection\\)${per_point_modes}," OR current MATCHES "PointRaster::(add|split|push|draw_tiles)"
       OR current MATCHES "(draw_tile_node|draw_tile_nodes|tile_nodes_of)<")
      set(per_point TRUE)
      math(EXPR per_point_functions "${per_point_functions} + 1")
    endif()
  elseif(line MATCHES "R_ARM_[A-Z0-9_]*(CALL|JUMP24|PC24)[ \t]+([^ \t]+)")  # ARM and Thumb calls
    set(callee "${CMAKE_MATCH_2}")
    if(callee MATCHES "${helper}")
      if(per_point)
        list(APPEND violations "${current} -> ${callee}")
      elseif(current MATCHES "draw_points<\\(stipple::Projection\\)2,")
        set(exact_divides TRUE)
      elseif(current MATCHES "build_shading_tables")
        set(control_found TRUE)
      endif()
    endif()
  endif()
endforeach()
if(per_point_functions EQUAL 0)
  message(FATAL_ERROR "no per-point function found in ${LIB}: the check would be vacuous")
endif()
if(NOT control_found)
  message(FATAL_ERROR "build_shading_tables calls no division helper: the helper calls are not being seen")
endif()
if(HW_DIVIDE AND NOT exact_divides)
  message(FATAL_ERROR "the exact-division mode calls no division helper in a build with STIPPLE_HW_DIVIDE on")
endif()
if(violations)
  list(REMOVE_DUPLICATES violations)
  string(REPLACE ";" "\n  " violations "${violations}")
  message(FATAL_ERROR "run-time helpers on the per-point path:\n  ${violations}")
endif()
message(STATUS "${per_point_functions} per-point functions (projection modes ${per_point_modes}), no division or floating-point helper")
