# Install rules, the CMake package and pkg-config files, man pages and the
# Debian packages (docs/install.md). Included by the top-level CMakeLists.txt
# after every target exists; not in the sanitizer build.
#
#   cmake --install build --prefix P      the whole tree under P (relocatable)
#   (cd build && cpack)                   build/packages/sss_*.deb, sss-dev_*.deb,
#                                         python3-sss_*.deb
#
# Layout under the prefix (GNUInstallDirs):
#   bin/                        the tools and sss-farm
#   share/sss/shaders/          the compiled standard shaders, their sources and headers
#   share/sss/scenes/           the bundled scenes (their run scripts take SSS_BIN_DIR)
#   <libdir>/sss/               the 2-D texture plugin
#   share/man/man1/             one page per tool (man/)
#   share/doc/sss/              README and docs/
#   include/sss/<module>/       the library's public headers
#   <libdir>/libsss_*.a         the library, one archive per module
#   <libdir>/cmake/sss/         find_package(sss): sss::sss (and sss::<module>)
#   <libdir>/pkgconfig/sss.pc   pkg-config --cflags --libs sss
# The tools find the shaders and the plugin relative to their own folder
# (sss/util/install_layout.h), so the tree works wherever it is moved.

include(CMakePackageConfigHelpers)

set(SSS_TOOLS ptbake ptfilter brickmake brickinfo render ptinfo ptsynth ptview shader sloinfo
  envdome ssprofile)
set(SSS_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/sss)

# --- runtime: tools, shaders, plugin, scenes, docs, man pages ---------------
install(TARGETS ${SSS_TOOLS} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT runtime)
install(PROGRAMS ${CMAKE_BINARY_DIR}/bin/sss-farm DESTINATION ${CMAKE_INSTALL_BINDIR}
  COMPONENT runtime)
install(TARGETS sss_texture2d LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}/sss
  COMPONENT runtime)
install(DIRECTORY ${CMAKE_BINARY_DIR}/shaders/ DESTINATION ${CMAKE_INSTALL_DATADIR}/sss/shaders
  COMPONENT runtime FILES_MATCHING PATTERN "*.slo" PATTERN "*.h" PATTERN CMakeFiles EXCLUDE)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/shaders/ DESTINATION ${CMAKE_INSTALL_DATADIR}/sss/shaders
  COMPONENT runtime FILES_MATCHING PATTERN "*.sl")
install(DIRECTORY ${PROJECT_SOURCE_DIR}/scenes/ DESTINATION ${CMAKE_INSTALL_DATADIR}/sss/scenes
  COMPONENT runtime USE_SOURCE_PERMISSIONS)
install(FILES ${PROJECT_SOURCE_DIR}/README.md DESTINATION ${CMAKE_INSTALL_DOCDIR}
  COMPONENT runtime)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs/ DESTINATION ${CMAKE_INSTALL_DOCDIR}
  COMPONENT runtime USE_SOURCE_PERMISSIONS)

# Man pages, written by hand in man/ (one per tool; tests/cli/test_man_pages.sh
# holds each to its tool's --help).
file(GLOB SSS_MAN_PAGES CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/man/*.1)
install(FILES ${SSS_MAN_PAGES} DESTINATION ${CMAKE_INSTALL_MANDIR}/man1 COMPONENT runtime)

# --- dev: headers, archives, CMake package, pkg-config ----------------------
get_property(SSS_MODULE_TARGETS GLOBAL PROPERTY SSS_MODULES)
install(TARGETS ${SSS_MODULE_TARGETS} sss_library EXPORT sssTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/sss DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
  COMPONENT dev FILES_MATCHING PATTERN "*.h")
install(EXPORT sssTargets NAMESPACE sss:: DESTINATION ${SSS_CMAKE_DIR} COMPONENT dev)
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/sssConfig.cmake.in
  ${CMAKE_BINARY_DIR}/cmake/sssConfig.cmake INSTALL_DESTINATION ${SSS_CMAKE_DIR})
write_basic_package_version_file(${CMAKE_BINARY_DIR}/cmake/sssConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_BINARY_DIR}/cmake/sssConfig.cmake
  ${CMAKE_BINARY_DIR}/cmake/sssConfigVersion.cmake DESTINATION ${SSS_CMAKE_DIR}
  COMPONENT dev)

# pkg-config: the prefix is found from the .pc file's own folder, so the
# installed tree stays relocatable. The archives in link order (each module
# before the ones it uses).
file(RELATIVE_PATH SSS_PC_TO_PREFIX /p/${CMAKE_INSTALL_LIBDIR}/pkgconfig /p)
string(REGEX REPLACE "/$" "" SSS_PC_TO_PREFIX "${SSS_PC_TO_PREFIX}")
set(SSS_PC_LIBS "")
foreach(module cli render bake binding shading rsl brick view image diffusion light dice scene cloud util)
  string(APPEND SSS_PC_LIBS " -lsss_${module}")
endforeach()
configure_file(${PROJECT_SOURCE_DIR}/cmake/sss.pc.in ${CMAKE_BINARY_DIR}/cmake/sss.pc @ONLY)
install(FILES ${CMAKE_BINARY_DIR}/cmake/sss.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig
  COMPONENT dev)

# --- Debian packages (cpack) -------------------------------------------------
# sss: the tools, shaders, scenes, docs and man pages; its library
# dependencies are found by dpkg-shlibdeps from the binaries. sss-dev: headers,
# archives and package files; it needs the -dev packages a program linking the
# archives needs.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME sss)
set(CPACK_PACKAGE_VENDOR "sss")
set(CPACK_PACKAGE_CONTACT "sss developers <sss@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
  "point-based subsurface scattering toolchain (bake, diffusion, brick maps, render)")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DIRECTORY ${CMAKE_BINARY_DIR}/packages)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_STRIP_FILES ON)
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_COMPONENTS_ALL runtime dev)
if(SSS_BUILD_PYTHON)
  list(APPEND CPACK_COMPONENTS_ALL python)
endif()
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION graphics)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_NAME sss)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_DEPENDS "python3")
set(CPACK_DEBIAN_RUNTIME_PACKAGE_RECOMMENDS "openimageio-tools")
set(CPACK_DEBIAN_DEV_PACKAGE_NAME sss-dev)
set(CPACK_DEBIAN_DEV_PACKAGE_SECTION libdevel)
set(CPACK_DEBIAN_DEV_PACKAGE_DEPENDS
  "sss (= ${PROJECT_VERSION}), libglm-dev, libtbb-dev, zlib1g-dev, libopenexr-dev, libembree-dev, libopenimageio-dev")
# python3-sss: the Python module (python/CMakeLists.txt installs it into
# Debian's dist-packages), built for this machine's python3 (3.11 on Debian 12).
set(CPACK_DEBIAN_PYTHON_PACKAGE_NAME python3-sss)
set(CPACK_DEBIAN_PYTHON_PACKAGE_SECTION python)
set(CPACK_DEBIAN_PYTHON_PACKAGE_DEPENDS
  "sss (= ${PROJECT_VERSION}), python3 (>= 3.11), python3 (<< 3.12), python3-numpy")
set(CPACK_COMPONENT_PYTHON_DESCRIPTION
  "The sss Python module: point clouds as numpy arrays, ptfilter's diffusion in-process,\n brick maps and texture3d lookups, frame patterns.")
set(CPACK_COMPONENT_RUNTIME_DESCRIPTION
  "The sss tools: ptbake, ptfilter, brickmake, brickinfo, render, ptinfo, ptsynth, ptview,\n shader, sloinfo, envdome, ssprofile and sss-farm, with the standard shaders, scenes, docs and man pages.")
set(CPACK_COMPONENT_DEV_DESCRIPTION
  "The sss library: headers, static archives, CMake package (find_package(sss))\n and pkg-config file.")
include(CPack)
