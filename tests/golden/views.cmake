# The golden images' views and sizes (regenerate_images.sh draws the same),
# and their pixels' CRC-32 from images.crc, for the tests of tests/ and
# tests/handheld/.
set(STIPPLE_GOLDEN_VIEWS "yaw0:0,0" "yaw90:90,20" "yaw210:210,35")
# size:format:projection; images in other projections than affine get the
# projection's name as a suffix (the exact one divides per point: with
# STIPPLE_HW_DIVIDE off it divides by multiplication, to the same bytes).
set(STIPPLE_GOLDEN_CONFIGS "240x320:rgb565:affine" "640x480:rgb888:affine" "240x320:rgb565:exact")
file(STRINGS ${CMAKE_CURRENT_LIST_DIR}/images.crc STIPPLE_GOLDEN_CRCS)

# Calls <callback>(name camera size format projection crc) for every golden image.
macro(stipple_foreach_golden callback)
  foreach(_view ${STIPPLE_GOLDEN_VIEWS})
    string(REPLACE ":" ";" _v ${_view})
    list(GET _v 0 _vname)
    list(GET _v 1 _vcam)
    foreach(_config ${STIPPLE_GOLDEN_CONFIGS})
      string(REPLACE ":" ";" _c ${_config})
      list(GET _c 0 _size)
      list(GET _c 1 _format)
      list(GET _c 2 _projection)
      set(_name bunny_${_vname}_${_size}_${_format})
      if(NOT _projection STREQUAL "affine")
        string(APPEND _name _${_projection})
      endif()
      set(_crc "")
      foreach(_line ${STIPPLE_GOLDEN_CRCS})
        if(_line MATCHES "^crc32 ([0-9a-f]+)  ${_name}\\.png$")
          set(_crc ${CMAKE_MATCH_1})
        endif()
      endforeach()
      if(_crc STREQUAL "")
        message(FATAL_ERROR "tests/golden/images.crc has no line for ${_name}.png")
      endif()
      cmake_language(CALL ${callback} ${_name} "${_vcam},3,35" ${_size} ${_format} ${_projection} ${_crc})
    endforeach()
  endforeach()
endmacro()

# The handheld program must print each golden image's CRC-32 (under the
# emulator in cross builds).
function(stipple_handheld_golden name camera size format projection crc)
  add_test(NAME handheld.golden.${name}
    COMMAND stipple-handheld ${PROJECT_SOURCE_DIR}/tests/golden/bunny_v1.spg --camera ${camera} --size ${size}
            --format ${format} --projection ${projection} --crc)
  set_tests_properties(handheld.golden.${name} PROPERTIES PASS_REGULAR_EXPRESSION "crc32 ${crc}")
endfunction()
