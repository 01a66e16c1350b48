# What `cmake --install` puts where (docs/install.md), and the .deb CPack
# makes of it.
#
#   bin/                     stipple, stipple-handheld, stipple-emulator, stipple-gl
#   lib/libstipple_{core,raster}.a, include/stipple/{core,raster}/*.h
#                            the handheld client library: find_package(stipple)
#                            gives stipple::core and stipple::raster; pkg-config's
#                            name is stipple
#   share/stipple/bunny.ply  the bundled scan `stipple demo` encodes
#   share/man/man1/*.1       from each program's --help (help2man), where found
include(CMakePackageConfigHelpers)

# The client library: core/ and raster/, their headers as "core/x.h" under
# include/stipple. stipple_warnings travels only as a link-time name of an
# empty interface (static libraries export their private links).
install(TARGETS stipple_core stipple_raster stipple_warnings EXPORT stippleTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
foreach(dir core raster)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${dir}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/stipple/${dir}
          FILES_MATCHING PATTERN "*.h" PATTERN "*.inc")
endforeach()
install(EXPORT stippleTargets NAMESPACE stipple:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/stipple)
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/stippleConfig.cmake.in
  ${PROJECT_BINARY_DIR}/stippleConfig.cmake INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/stipple)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/stippleConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/stippleConfig.cmake ${PROJECT_BINARY_DIR}/stippleConfigVersion.cmake
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/stipple)
# pkg-config: the same library and the build's 0/1 options as macros.
set(STIPPLE_PC_HW_DIVIDE 0)
set(STIPPLE_PC_CHECK_RANGES 0)
if(STIPPLE_HW_DIVIDE)
  set(STIPPLE_PC_HW_DIVIDE 1)
endif()
if(STIPPLE_CHECK_RANGES)
  set(STIPPLE_PC_CHECK_RANGES 1)
endif()
file(RELATIVE_PATH STIPPLE_PC_UP /p/${CMAKE_INSTALL_LIBDIR}/pkgconfig /p)  # from the .pc file to the prefix
configure_file(${PROJECT_SOURCE_DIR}/cmake/stipple.pc.in ${PROJECT_BINARY_DIR}/stipple.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/stipple.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)

# The bundled scan and what it may be used under.
install(FILES ${PROJECT_SOURCE_DIR}/data/bunny.ply ${PROJECT_SOURCE_DIR}/data/README.md
        DESTINATION ${CMAKE_INSTALL_DATADIR}/stipple)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/data/licenses DESTINATION ${CMAKE_INSTALL_DATADIR}/stipple)

# Man pages from --help, for the programs this build makes (tools/ calls
# stipple_man_page once each program exists). A cross build's programs do
# not run here: no pages.
find_program(HELP2MAN_EXECUTABLE help2man)
function(stipple_man_page target summary)
  if(NOT HELP2MAN_EXECUTABLE OR CMAKE_CROSSCOMPILING)
    return()
  endif()
  set(page ${PROJECT_BINARY_DIR}/man/${target}.1)
  # --version-string: the viewers' --help is all help2man needs to run.
  add_custom_command(OUTPUT ${page}
    COMMAND ${CMAKE_COMMAND} -E make_directory ${PROJECT_BINARY_DIR}/man
    COMMAND ${CMAKE_COMMAND} -E env ASAN_OPTIONS=detect_leaks=0 SDL_VIDEODRIVER=dummy
            ${HELP2MAN_EXECUTABLE} --no-info --no-discard-stderr --version-string=${PROJECT_VERSION}
            --name=${summary} --output=${page} $<TARGET_FILE:${target}>
    DEPENDS ${target} VERBATIM)
  add_custom_target(${target}_man ALL DEPENDS ${page})
  install(FILES ${page} DESTINATION ${CMAKE_INSTALL_MANDIR}/man1)
endfunction()
# stipple-VERB.1 from `stipple VERB --help`, through a two-line script that
# is `stipple VERB` (help2man runs one program).
function(stipple_verb_man_page verb summary)
  if(NOT HELP2MAN_EXECUTABLE OR CMAKE_CROSSCOMPILING)
    return()
  endif()
  set(script ${PROJECT_BINARY_DIR}/man/bin/stipple-${verb})
  file(GENERATE OUTPUT ${script} CONTENT "#!/bin/sh\nexec '$<TARGET_FILE:stipple>' ${verb} \"$@\"\n"
       FILE_PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE GROUP_READ GROUP_EXECUTE WORLD_READ WORLD_EXECUTE)
  set(page ${PROJECT_BINARY_DIR}/man/stipple-${verb}.1)
  add_custom_command(OUTPUT ${page}
    COMMAND ${CMAKE_COMMAND} -E env ASAN_OPTIONS=detect_leaks=0
            ${HELP2MAN_EXECUTABLE} --no-info --version-string=${PROJECT_VERSION} --name=${summary} --output=${page} ${script}
    DEPENDS stipple VERBATIM)
  add_custom_target(stipple-${verb}_man ALL DEPENDS ${page})
  install(FILES ${page} DESTINATION ${CMAKE_INSTALL_MANDIR}/man1)
endfunction()

# The .deb: `cpack -G DEB` in the build folder (docs/install.md).
set(CPACK_PACKAGE_NAME stipple)
set(CPACK_PACKAGE_VENDOR "stipple")
set(CPACK_PACKAGE_CONTACT "stipple developers <stipple@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "dense 3-D scans as streamed Gaussians, drawn in fixed point on handhelds")
set(CPACK_PACKAGE_DESCRIPTION "stipple encodes scanned point clouds into a hierarchy of anisotropic Gaussians (.spg), serves view-dependent cuts of it over TCP or a serial line, and draws them with a fixed-point, allocation-free client; an SDL2 emulator of the handheld and a GL desktop client read the same stream.")
set(CPACK_GENERATOR DEB)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION graphics)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)  # libpng, SDL2, epoxy, liblzf from dpkg-shlibdeps
set(CPACK_PACKAGE_INSTALL_DIRECTORY stipple)
include(CPack)
