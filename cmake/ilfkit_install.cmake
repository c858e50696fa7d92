# ilfkit_install.cmake - what an install gives a program that uses ilfkit's libraries: the shared
# libraries relight and capture beside lfio (lfio/CMakeLists.txt), their pkg-config files and the
# CMake package `ilfkit` (find_package(ilfkit COMPONENTS lfio relight capture)).
#
# Invariants: an installed shared library exports only its public API (its prefix followed by a
# letter: rl_*, cap_*, lfio_*); the prefix__ internals and the static floors it embeds (ilfbase,
# ilfread, image) stay local, so two of them in one program never clash. Each .pc file finds its
# prefix relative to itself (an installed tree can move) and carries an rpath to the installed
# libraries, so a program linked through it runs without LD_LIBRARY_PATH.
include(CMakePackageConfigHelpers)

# pkg-config's path from LIBDIR/pkgconfig back to the prefix ("../..").
file(RELATIVE_PATH ILFKIT_PC_TO_PREFIX "/${CMAKE_INSTALL_LIBDIR}/pkgconfig" "/")
string(REGEX REPLACE "/$" "" ILFKIT_PC_TO_PREFIX "${ILFKIT_PC_TO_PREFIX}")
# No rpath when the libraries go to a folder the linker and loader search anyway.
set(ILFKIT_PC_RPATH "-Wl,-rpath,\${libdir} ")
if("${CMAKE_INSTALL_FULL_LIBDIR}" IN_LIST CMAKE_C_IMPLICIT_LINK_DIRECTORIES)
  set(ILFKIT_PC_RPATH "")
endif()

# ilfkit_install_pkgconfig(NAME DESCRIPTION REQUIRES LIBS_PRIVATE): installs NAME.pc for libNAME.
function(ilfkit_install_pkgconfig name description requires libs_private)
  set(PC_NAME ${name})
  set(PC_DESCRIPTION ${description})
  set(PC_FIELDS "")  # the optional fields, only when given
  if(requires)
    string(APPEND PC_FIELDS "Requires: ${requires}\n")
  endif()
  if(libs_private)
    string(APPEND PC_FIELDS "Libs.private: ${libs_private}\n")
  endif()
  configure_file(${PROJECT_SOURCE_DIR}/cmake/ilfkit.pc.in ${CMAKE_CURRENT_BINARY_DIR}/${name}.pc @ONLY)
  install(FILES ${CMAKE_CURRENT_BINARY_DIR}/${name}.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
endfunction()

# ilfkit_version_script(TARGET PREFIX): TARGET exports only PREFIX followed by a lowercase letter,
# in the version node PREFIX_0 (LFIO_0, RL_0, CAP_0).
function(ilfkit_version_script target prefix)
  string(REGEX REPLACE "_$" "" tag ${prefix})
  string(TOUPPER ${tag} tag)
  set(script ${CMAKE_CURRENT_BINARY_DIR}/${target}.map)
  file(WRITE ${script} "/* Symbols exported by lib${target}: the public API only. */\n"
                       "${tag}_0 {\n  global: ${prefix}[a-z]*;\n  local: *;\n};\n")
  target_link_options(${target} PRIVATE -Wl,--version-script=${script})
  set_property(TARGET ${target} APPEND PROPERTY LINK_DEPENDS ${script})
endfunction()

# ilfkit_add_shared_twin(NAME PREFIX DESCRIPTION): NAME_objects (an OBJECT library, made position-independent
# here) is compiled once and archived as the static NAME (made here), which ilf and the tests link (tests reach
# internals); this makes from the same objects the shared libNAME.so.MAJOR, installed with the
# headers of include/NAME, NAME.pc (Requires: lfio) and the target ilfkit::NAME.
function(ilfkit_add_shared_twin name prefix description)
  # The objects serve the shared twin too, so they are position-independent; -fno-semantic-interposition
  # keeps the inlining across the library's own functions that a program's (PIE) build has.
  set_target_properties(${name}_objects PROPERTIES POSITION_INDEPENDENT_CODE ON)
  if(CMAKE_C_COMPILER_ID MATCHES "GNU|Clang")
    target_compile_options(${name}_objects PRIVATE -fno-semantic-interposition)
  endif()
  add_library(${name} STATIC)
  target_link_libraries(${name} PUBLIC ${name}_objects)
  add_library(${name}_shared SHARED)
  target_link_libraries(${name}_shared PRIVATE ${name}_objects PUBLIC lfio::lfio)
  target_include_directories(${name}_shared INTERFACE
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
    $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/base/include>  # ilf/limits.h, installed beside the headers
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  set_target_properties(${name}_shared PROPERTIES
    OUTPUT_NAME ${name} EXPORT_NAME ${name}
    VERSION ${PROJECT_VERSION} SOVERSION ${PROJECT_VERSION_MAJOR})
  ilfkit_version_script(${name}_shared ${prefix})
  # Every symbol resolved at link time (not under sanitizers, whose runtime lives in the executable).
  if(NOT ILFKIT_SANITIZE AND NOT ILFKIT_FUZZ)
    target_link_options(${name}_shared PRIVATE LINKER:-z,defs)
  endif()
  install(TARGETS ${name}_shared EXPORT ilfkitTargets
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
    RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  install(DIRECTORY include/${name} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  ilfkit_install_pkgconfig(${name} "${description}" lfio "")
endfunction()

# The package itself, once every library is defined (top-level CMakeLists.txt calls this last).
function(ilfkit_install_package)
  # The one header of base that the public headers include: the limits they name.
  install(FILES ${PROJECT_SOURCE_DIR}/base/include/ilf/limits.h DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/ilf)
  set(dir ${CMAKE_INSTALL_LIBDIR}/cmake/ilfkit)
  install(EXPORT ilfkitTargets NAMESPACE ilfkit:: DESTINATION ${dir})
  configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/ilfkitConfig.cmake.in
    ${PROJECT_BINARY_DIR}/ilfkitConfig.cmake INSTALL_DESTINATION ${dir})
  write_basic_package_version_file(${PROJECT_BINARY_DIR}/ilfkitConfigVersion.cmake
    VERSION ${PROJECT_VERSION} COMPATIBILITY SameMajorVersion)
  install(FILES ${PROJECT_BINARY_DIR}/ilfkitConfig.cmake ${PROJECT_BINARY_DIR}/ilfkitConfigVersion.cmake
    DESTINATION ${dir})
endfunction()
