# Install rules and the package files (included from the top-level CMakeLists.txt).
#
#   cmake --install BUILD --prefix PREFIX    installs
#     bin/irrcache                                   the command
#     include/irrcache/*.h                           the public headers (nothing from src/)
#     lib/libic_core.a, libirrcache_cache.a, …       the libraries (static; shared with -DBUILD_SHARED_LIBS=ON)
#     lib/cmake/irrcache/irrcacheConfig*.cmake       find_package(irrcache 0.5 REQUIRED [COMPONENTS cache render])
#     lib/pkgconfig/irrcache.pc, irrcache-cache.pc   pkg-config --cflags --libs irrcache-cache
#     share/man/man1/irrcache.1                      the manual page, made from the command's --help texts
#     share/doc/irrcache/README.md, docs/*.md        the documentation
#
# Exported targets (namespace irrcache::): core (ic_core), cache (irrcache_cache: the cache and gathering,
# ic_core, libm and threads only), image (irrcache_image), render (irrcache: the renderer), and the
# command irrcache::irrcache. The libraries are static, so the renderer's private dependencies (Embree,
# assimp, cJSON, OpenEXR, zlib, libxml2) and the image library's (OpenEXR, libjpeg) appear in their link
# interfaces and irrcacheConfig.cmake finds them.
include(CMakePackageConfigHelpers)

# The same names for a project that takes irrcache in with add_subdirectory.
add_library(irrcache::core ALIAS ic_core)
add_library(irrcache::cache ALIAS irrcache_cache)
if(NOT IRRCACHE_CACHE_ONLY)
  add_library(irrcache::image ALIAS irrcache_image)
  add_library(irrcache::render ALIAS irrcache)
  add_executable(irrcache::irrcache ALIAS irrcache_cli)
endif()

set(IC_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/irrcache)
set(IC_INSTALL_LIBRARIES ic_core irrcache_cache)
set_target_properties(ic_core PROPERTIES EXPORT_NAME core)
set_target_properties(irrcache_cache PROPERTIES EXPORT_NAME cache)
if(NOT IRRCACHE_CACHE_ONLY)
  list(APPEND IC_INSTALL_LIBRARIES irrcache_image irrcache)
  set_target_properties(irrcache_image PROPERTIES EXPORT_NAME image)
  set_target_properties(irrcache PROPERTIES EXPORT_NAME render)
  set_target_properties(irrcache_cli PROPERTIES EXPORT_NAME irrcache)
  install(TARGETS irrcache_cli EXPORT irrcacheTargets RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  # The manual page runs the built command for its --help texts (not where the build cannot run it).
  if(NOT CMAKE_CROSSCOMPILING)
    add_custom_command(OUTPUT ${PROJECT_BINARY_DIR}/irrcache.1
      COMMAND bash ${PROJECT_SOURCE_DIR}/scripts/make-man.sh $<TARGET_FILE:irrcache_cli> ${PROJECT_BINARY_DIR}/irrcache.1
      DEPENDS irrcache_cli ${PROJECT_SOURCE_DIR}/scripts/make-man.sh
      COMMENT "Manual page irrcache.1 from the command's --help")
    add_custom_target(irrcache_man ALL DEPENDS ${PROJECT_BINARY_DIR}/irrcache.1)
    install(FILES ${PROJECT_BINARY_DIR}/irrcache.1 DESTINATION ${CMAKE_INSTALL_MANDIR}/man1)
  endif()
  install(FILES README.md DESTINATION ${CMAKE_INSTALL_DOCDIR})
  install(DIRECTORY docs/ DESTINATION ${CMAKE_INSTALL_DOCDIR}/docs FILES_MATCHING PATTERN "*.md")
endif()
install(TARGETS ${IC_INSTALL_LIBRARIES} EXPORT irrcacheTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
# The cache-only install carries only the headers its libraries implement.
if(IRRCACHE_CACHE_ONLY)
  install(FILES include/irrcache/cache.h include/irrcache/comm.h include/irrcache/common.h
                include/irrcache/defaults.h include/irrcache/gather.h include/irrcache/hsh.h
                include/irrcache/version.h
          DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/irrcache)
else()
  install(DIRECTORY include/irrcache DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} FILES_MATCHING PATTERN "*.h")
endif()
install(EXPORT irrcacheTargets NAMESPACE irrcache:: DESTINATION ${IC_INSTALL_CMAKEDIR})

# 0.x: a minor release may change the API, so only the same minor version is compatible.
if(PROJECT_VERSION_MAJOR EQUAL 0)
  set(IC_VERSION_COMPATIBILITY SameMinorVersion)
else()
  set(IC_VERSION_COMPATIBILITY SameMajorVersion)
endif()
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/irrcacheConfig.cmake.in
  ${PROJECT_BINARY_DIR}/irrcacheConfig.cmake INSTALL_DESTINATION ${IC_INSTALL_CMAKEDIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/irrcacheConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY ${IC_VERSION_COMPATIBILITY})
install(FILES ${PROJECT_BINARY_DIR}/irrcacheConfig.cmake ${PROJECT_BINARY_DIR}/irrcacheConfigVersion.cmake
        DESTINATION ${IC_INSTALL_CMAKEDIR})

# pkg-config: the prefix is found from the .pc file's own place (${pcfiledir}), so the files stay right
# under `cmake --install --prefix` and when the installed tree is moved.
file(RELATIVE_PATH IC_PC_TO_PREFIX "/prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig" "/prefix")
string(REGEX REPLACE "/$" "" IC_PC_TO_PREFIX "${IC_PC_TO_PREFIX}")
set(IC_PC_PREFIX "\${pcfiledir}/${IC_PC_TO_PREFIX}")
set(IC_PC_LIBDIR "\${prefix}/${CMAKE_INSTALL_LIBDIR}")
set(IC_PC_INCLUDEDIR "\${prefix}/${CMAKE_INSTALL_INCLUDEDIR}")
if(IS_ABSOLUTE "${CMAKE_INSTALL_LIBDIR}" OR IS_ABSOLUTE "${CMAKE_INSTALL_INCLUDEDIR}")
  message(FATAL_ERROR "irrcache: the pkg-config files need CMAKE_INSTALL_LIBDIR and CMAKE_INSTALL_INCLUDEDIR "
                      "relative to the install prefix")
endif()
set(IC_PC_FILES irrcache-cache)
if(NOT IRRCACHE_CACHE_ONLY)
  list(APPEND IC_PC_FILES irrcache)
endif()
foreach(pc ${IC_PC_FILES})
  configure_file(${PROJECT_SOURCE_DIR}/cmake/${pc}.pc.in ${PROJECT_BINARY_DIR}/${pc}.pc @ONLY)
  install(FILES ${PROJECT_BINARY_DIR}/${pc}.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
endforeach()
