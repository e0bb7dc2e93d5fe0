# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
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
#   share/sss/farm/sss_farm/    sss-farm's Python package (bin/sss-farm finds it)
#   <libdir>/sss/               the 2-D texture plugin
#   share/man/man1/             one page per tool (man/), gzipped
#   share/doc/<package>/        README, docs/, copyright, changelog.gz
#   include/sss/<module>/       the library's public headers (not the command line's)
#   <libdir>/libsss.so.*        the shared library (sss::sss)
#   <libdir>/libsss_*.a         the library, one archive per module (sss::<module>)
#   <libdir>/cmake/sss/         find_package(sss [COMPONENTS module...])
#   <libdir>/pkgconfig/         sss.pc (shared) and sss-static.pc (the archives)
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
# sss-farm's package, the listed modules only (never a __pycache__).
install(FILES ${SSS_FARM_PACKAGE_FILES} DESTINATION ${CMAKE_INSTALL_DATADIR}/sss/farm/sss_farm
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
# holds each to its tool's --help), installed gzipped without a time stamp as
# Debian's tools do.
find_program(SSS_GZIP gzip REQUIRED)
file(GLOB SSS_MAN_PAGES CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/man/*.1)
set(SSS_MAN_GZ "")
foreach(page ${SSS_MAN_PAGES})
  get_filename_component(name ${page} NAME)
  set(gz ${CMAKE_BINARY_DIR}/man/man1/${name}.gz)
  add_custom_command(OUTPUT ${gz}
    COMMAND ${CMAKE_COMMAND} -E make_directory ${CMAKE_BINARY_DIR}/man/man1
    COMMAND ${SSS_GZIP} -9n -c ${page} > ${gz}
    DEPENDS ${page}
    COMMENT "Man page ${name}.gz")
  list(APPEND SSS_MAN_GZ ${gz})
endforeach()
add_custom_target(sss_man ALL DEPENDS ${SSS_MAN_GZ})
install(FILES ${SSS_MAN_GZ} DESTINATION ${CMAKE_INSTALL_MANDIR}/man1 COMPONENT runtime)

# --- library: the shared library ----------------------------------------------
# libsss0.1: libsss.so.0.1 alone (its own package, as Debian policy wants a
# shared library); the libsss.so link is sss-dev's.
if(SSS_BUILD_SHARED)
  install(TARGETS sss_shared EXPORT sssTargets
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT library NAMELINK_SKIP)
  install(TARGETS sss_shared EXPORT sssTargets
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev NAMELINK_ONLY)
  install(EXPORT sssTargets NAMESPACE sss:: DESTINATION ${SSS_CMAKE_DIR} COMPONENT dev)
endif()

# --- dev: headers, archives, CMake package, pkg-config ----------------------
# The public API's headers: every module's but the command line's and
# ptview -serve's (cli is the tools' option parsing, serve ptview's web page:
# front ends, not an API).
get_property(SSS_MODULE_NAMES GLOBAL PROPERTY SSS_MODULE_NAMES)
set(SSS_PUBLIC_MODULES ${SSS_MODULE_NAMES})
list(REMOVE_ITEM SSS_PUBLIC_MODULES cli serve)
foreach(module ${SSS_PUBLIC_MODULES})
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/sss/${module}
    DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/sss COMPONENT dev FILES_MATCHING PATTERN "*.h")
endforeach()

# One export file per module archive, and a table of what each one needs
# (sssModules.cmake), so that find_package(sss COMPONENTS diffusion) looks up
# the packages of diffusion and the modules below it only. The package each
# imported target comes from:
set(SSS_PACKAGE_OF_glm::glm "glm CONFIG")
set(SSS_PACKAGE_OF_TBB::tbb "TBB CONFIG")
set(SSS_PACKAGE_OF_Threads::Threads "Threads")
set(SSS_PACKAGE_OF_ZLIB::ZLIB "ZLIB")
set(SSS_PACKAGE_OF_embree "embree 3 CONFIG")
set(SSS_PACKAGE_OF_OpenImageIO::OpenImageIO "OpenImageIO CONFIG")
set(SSS_PACKAGE_OF_OpenEXR::OpenEXR "OpenEXR CONFIG")
set(SSS_PACKAGE_OF_Imath::Imath "Imath CONFIG")
set(SSS_MODULES_TABLE "# Generated by cmake/install.cmake: each module's modules and packages.\n")
string(APPEND SSS_MODULES_TABLE "set(_sss_modules ${SSS_PUBLIC_MODULES})\n")
foreach(module ${SSS_PUBLIC_MODULES})
  install(TARGETS sss_${module} EXPORT sss_${module}Targets
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev)
  install(EXPORT sss_${module}Targets NAMESPACE sss:: DESTINATION ${SSS_CMAKE_DIR}
    COMPONENT dev)
  get_property(uses GLOBAL PROPERTY SSS_MODULE_USES_${module})
  get_target_property(links sss_${module} LINK_LIBRARIES)
  set(packages "")
  foreach(link ${links})
    # Modules, and libraries named by their path (OpenVDB: Debian ships no
    # CMake package for it), which the export file keeps as they are.
    if(link MATCHES "^sss_" OR link STREQUAL "${CMAKE_DL_LIBS}" OR IS_ABSOLUTE "${link}")
      continue()
    endif()
    if(NOT DEFINED SSS_PACKAGE_OF_${link})
      message(FATAL_ERROR "cmake/install.cmake: which package gives ${link} (linked by "
        "sss_${module})? Add it to the SSS_PACKAGE_OF_ table.")
    endif()
    list(APPEND packages "${SSS_PACKAGE_OF_${link}}")
  endforeach()
  string(APPEND SSS_MODULES_TABLE "set(_sss_uses_${module} ${uses})\n")
  string(APPEND SSS_MODULES_TABLE "set(_sss_packages_${module}")
  foreach(package ${packages})
    string(APPEND SSS_MODULES_TABLE " \"${package}\"")
  endforeach()
  string(APPEND SSS_MODULES_TABLE ")\n")
endforeach()
file(WRITE ${CMAKE_BINARY_DIR}/cmake/sssModules.cmake "${SSS_MODULES_TABLE}")
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/sssConfig.cmake.in
  ${CMAKE_BINARY_DIR}/cmake/sssConfig.cmake INSTALL_DESTINATION ${SSS_CMAKE_DIR})
write_basic_package_version_file(${CMAKE_BINARY_DIR}/cmake/sssConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_BINARY_DIR}/cmake/sssConfig.cmake
  ${CMAKE_BINARY_DIR}/cmake/sssConfigVersion.cmake ${CMAKE_BINARY_DIR}/cmake/sssModules.cmake
  DESTINATION ${SSS_CMAKE_DIR} COMPONENT dev)

# pkg-config: sss (the shared library) and sss-static (the archives in link
# order, each module before the ones it uses). The prefix is found from the
# .pc file's own folder, so the installed tree stays relocatable.
file(RELATIVE_PATH SSS_PC_TO_PREFIX /p/${CMAKE_INSTALL_LIBDIR}/pkgconfig /p)
string(REGEX REPLACE "/$" "" SSS_PC_TO_PREFIX "${SSS_PC_TO_PREFIX}")
set(SSS_PC_LIBS "")
foreach(module render bake binding shading rsl vdb brick view image truth diffusion light dice
    scene cloud util)
  string(APPEND SSS_PC_LIBS " -lsss_${module}")
endforeach()
foreach(pc sss sss-static)
  configure_file(${PROJECT_SOURCE_DIR}/cmake/${pc}.pc.in ${CMAKE_BINARY_DIR}/cmake/${pc}.pc @ONLY)
  install(FILES ${CMAKE_BINARY_DIR}/cmake/${pc}.pc
    DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig COMPONENT dev)
endforeach()

# --- Debian packages (cpack) -------------------------------------------------
# sss: the tools, shaders, scenes, docs and man pages; libsss0.1: the shared
# library; sss-dev: headers, archives, the libsss.so link and package files;
# python3-sss: the Python module. Library dependencies are found by
# dpkg-shlibdeps from the binaries. Every package has the copyright file and
# the changelog in /usr/share/doc/<package>/ (lintian accepts them without an
# error: tests/install/test_deb.sh). SSS_PACKAGE_MAINTAINER names who builds
# the packages: a studio building its own sets its own address.
set(SSS_PACKAGE_MAINTAINER "The sss Authors <sss-maintainers@example.org>" CACHE STRING
  "The Maintainer field of the Debian packages (Name <address>)")
set(SSS_DEB_LIBRARY libsss${PROJECT_VERSION_MAJOR}.${PROJECT_VERSION_MINOR})
set(SSS_DEB_PACKAGES sss sss-dev)
if(SSS_BUILD_SHARED)
  list(APPEND SSS_DEB_PACKAGES ${SSS_DEB_LIBRARY})
endif()
if(SSS_BUILD_PYTHON)
  list(APPEND SSS_DEB_PACKAGES python3-sss)
endif()
# The changelog (packaging/debian/changelog, with this version and
# maintainer), gzipped without a time stamp as Debian's tools do.
configure_file(${PROJECT_SOURCE_DIR}/packaging/debian/changelog.in
  ${CMAKE_BINARY_DIR}/packaging/changelog @ONLY)
add_custom_command(OUTPUT ${CMAKE_BINARY_DIR}/packaging/changelog.gz
  COMMAND ${SSS_GZIP} -9nf -k ${CMAKE_BINARY_DIR}/packaging/changelog
  DEPENDS ${CMAKE_BINARY_DIR}/packaging/changelog VERBATIM)
add_custom_target(sss_changelog ALL DEPENDS ${CMAKE_BINARY_DIR}/packaging/changelog.gz)
foreach(package ${SSS_DEB_PACKAGES})
  if(package STREQUAL "sss")
    set(component runtime)
  elseif(package STREQUAL "sss-dev")
    set(component dev)
  elseif(package STREQUAL "python3-sss")
    set(component python)
  else()
    set(component library)
  endif()
  install(FILES ${PROJECT_SOURCE_DIR}/packaging/debian/copyright
    ${CMAKE_BINARY_DIR}/packaging/changelog.gz
    DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/${package} COMPONENT ${component})
endforeach()
install(FILES ${PROJECT_SOURCE_DIR}/LICENSE ${PROJECT_SOURCE_DIR}/NOTICE
  DESTINATION ${CMAKE_INSTALL_DOCDIR} COMPONENT runtime)

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME sss)
set(CPACK_PACKAGE_VENDOR "The sss Authors")
set(CPACK_PACKAGE_CONTACT "${SSS_PACKAGE_MAINTAINER}")
set(CPACK_DEBIAN_PACKAGE_MAINTAINER "${SSS_PACKAGE_MAINTAINER}")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DIRECTORY ${CMAKE_BINARY_DIR}/packages)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_STRIP_FILES ON)
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_COMPONENTS_ALL runtime dev)
if(SSS_BUILD_SHARED)
  list(APPEND CPACK_COMPONENTS_ALL library)
endif()
if(SSS_BUILD_PYTHON)
  list(APPEND CPACK_COMPONENTS_ALL python)
endif()
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION graphics)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_NAME sss)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_DEPENDS "python3")
set(CPACK_DEBIAN_RUNTIME_PACKAGE_RECOMMENDS "openimageio-tools")
set(CPACK_DEBIAN_LIBRARY_PACKAGE_NAME ${SSS_DEB_LIBRARY})
set(CPACK_DEBIAN_LIBRARY_PACKAGE_SECTION libs)
set(CPACK_DEBIAN_PACKAGE_GENERATE_SHLIBS ON)
# ldconfig by dpkg's trigger (packaging/debian/library/triggers) rather than
# from maintainer scripts; the scripts given here replace cpack's, which
# would call ldconfig themselves.
set(CPACK_DEBIAN_LIBRARY_PACKAGE_CONTROL_EXTRA
  ${PROJECT_SOURCE_DIR}/packaging/debian/library/triggers
  ${PROJECT_SOURCE_DIR}/packaging/debian/library/postinst
  ${PROJECT_SOURCE_DIR}/packaging/debian/library/postrm)
# The symbols file of libsss0.1: every exported symbol with the version that
# brought it, made by dpkg-gensymbols from the built library (dpkg-dev), so
# that a package built against it depends on the version it needs. Made at
# build time, not kept in the tree: while the version is 0.x the exported
# functions change with the code, and the soname changes with each minor.
if(SSS_BUILD_SHARED)
  find_program(SSS_GENSYMBOLS dpkg-gensymbols REQUIRED)
  set(SSS_SYMBOLS_DIR ${CMAKE_BINARY_DIR}/packaging/gensymbols)
  file(WRITE ${SSS_SYMBOLS_DIR}/debian/control
    "Source: sss\n\nPackage: ${SSS_DEB_LIBRARY}\nArchitecture: any\n")
  add_custom_command(OUTPUT ${CMAKE_BINARY_DIR}/packaging/symbols
    COMMAND ${SSS_GENSYMBOLS} -q -p${SSS_DEB_LIBRARY} -v${PROJECT_VERSION}
            -e$<TARGET_FILE:sss_shared> -O${CMAKE_BINARY_DIR}/packaging/symbols
    WORKING_DIRECTORY ${SSS_SYMBOLS_DIR}
    DEPENDS sss_shared
    COMMENT "Debian symbols file of libsss"
    VERBATIM)
  add_custom_target(sss_symbols ALL DEPENDS ${CMAKE_BINARY_DIR}/packaging/symbols)
  list(APPEND CPACK_DEBIAN_LIBRARY_PACKAGE_CONTROL_EXTRA ${CMAKE_BINARY_DIR}/packaging/symbols)
endif()
set(CPACK_DEBIAN_LIBRARY_PACKAGE_CONTROL_STRICT_PERMISSION ON)
set(CPACK_DEBIAN_PACKAGE_GENERATE_SHLIBS_POLICY "=")
set(CPACK_DEBIAN_DEV_PACKAGE_NAME sss-dev)
set(CPACK_DEBIAN_DEV_PACKAGE_SECTION libdevel)
set(SSS_DEV_DEPENDS "libglm-dev, libtbb-dev, zlib1g-dev, libopenexr-dev, libembree-dev, libopenimageio-dev, libopenvdb-dev")
if(SSS_BUILD_SHARED)
  set(SSS_DEV_DEPENDS "${SSS_DEB_LIBRARY} (= ${PROJECT_VERSION}), ${SSS_DEV_DEPENDS}")
endif()
set(CPACK_DEBIAN_DEV_PACKAGE_DEPENDS "${SSS_DEV_DEPENDS}")
# python3-sss: the Python module (python/CMakeLists.txt installs it into
# Debian's dist-packages), built for this machine's python3 (3.11 on Debian 12).
set(CPACK_DEBIAN_PYTHON_PACKAGE_NAME python3-sss)
set(CPACK_DEBIAN_PYTHON_PACKAGE_SECTION python)
set(CPACK_DEBIAN_PYTHON_PACKAGE_DEPENDS
  "sss (= ${PROJECT_VERSION}), python3 (>= 3.11), python3 (<< 3.12), python3-numpy")
# Each package's summary (under 80 columns), then its description. No
# CPACK_PACKAGE_DESCRIPTION_SUMMARY: cpack would put it before each.
set(CPACK_DEBIAN_RUNTIME_DESCRIPTION "point-based subsurface scattering toolchain
The sss tools re-create RenderMan's point-based subsurface scattering
pipeline: ptbake bakes point clouds from RIB scenes, ptfilter computes
the diffusion, brickmake builds brick maps, render ray-traces RIB scenes
with RenderMan Shading Language shaders, and sss-farm runs the chain on
a Slurm farm. With the standard shaders, scenes, docs and man pages.")
set(CPACK_DEBIAN_LIBRARY_DESCRIPTION "point-based subsurface scattering library
The shared library of the sss toolchain: point clouds, the diffusion,
brick maps, the shading language and the renderer, for programs that
embed them.")
set(CPACK_DEBIAN_DEV_DESCRIPTION "point-based subsurface scattering library (development files)
Headers of the sss library's public API, the libsss.so link, the static
archives of its modules, the CMake package (find_package(sss)) and the
pkg-config files (sss, sss-static).")
set(CPACK_DEBIAN_PYTHON_DESCRIPTION "point-based subsurface scattering (Python module)
The sss Python module: point clouds as numpy arrays, the diffusion
in-process, brick maps and texture3d lookups, frame patterns.")
include(CPack)
