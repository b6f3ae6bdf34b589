# Install layout (FHS, prefix /usr for the packages) and the .deb packages.
#
#   /usr/bin/aprt                                the runtime
#   /usr/share/aprt/{config,model_bin,data}      default configuration, DBC, IDL, the
#                                                shipped model and demo drive
#   /etc/aprt/aprt.yaml                          the ECU's configuration (conffile)
#   /usr/lib/systemd/system/aprt.service         the unit
#   /usr/include/aprt/...                        engine headers        (aprt-dev)
#   /usr/lib/<multiarch>/libaprt_*.a             engine libraries      (aprt-dev)
#   /usr/lib/<multiarch>/cmake/aprt/             find_package(aprt)    (aprt-dev)
#
# cpack -G DEB in a build directory makes aprt_<v>_<arch>.deb and
# aprt-dev_<v>_<arch>.deb for the build's target (amd64 natively, arm64 with
# the aarch64 preset); tools/package_smoke.sh checks them.
# The packages install to /usr, so does `cmake --install` unless told otherwise
# (use DESTDIR or --prefix): with prefix /usr GNUInstallDirs picks the
# multiarch library folder and puts the configuration in /etc.
if(CMAKE_INSTALL_PREFIX_INITIALIZED_TO_DEFAULT)
  set(CMAKE_INSTALL_PREFIX /usr CACHE PATH "Install prefix" FORCE)
endif()
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(APRT_INSTALL_DATADIR ${CMAKE_INSTALL_DATADIR}/aprt)
set(APRT_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/aprt)

install(TARGETS aprt RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT runtime)
# The driver modules (libcamera, DDS), found from the binary as ../lib/aprt/.
if(TARGET aprt_libcamera)
  install(TARGETS aprt_libcamera LIBRARY DESTINATION lib/aprt COMPONENT runtime)
endif()
if(TARGET aprt_dds_module)
  install(TARGETS aprt_dds_module LIBRARY DESTINATION lib/aprt COMPONENT runtime)
endif()
install(FILES config/default.yaml config/autoware.yaml config/aprt_pose.dbc
              config/vehicle_odometry_example.dbc config/aprt.service
        DESTINATION ${APRT_INSTALL_DATADIR}/config COMPONENT runtime)
install(DIRECTORY config/idl DESTINATION ${APRT_INSTALL_DATADIR}/config COMPONENT runtime)
# (A candidate model not yet shipped, model_bin/*_candidate.aprt, and a
# training run's weights kept to continue it elsewhere, *_partial.aprt, stay out.)
install(DIRECTORY model_bin/ DESTINATION ${APRT_INSTALL_DATADIR}/model_bin COMPONENT runtime
        FILES_MATCHING PATTERN "*.aprt" PATTERN "*.json" PATTERN "*.md"
        PATTERN "*_candidate.aprt" EXCLUDE PATTERN "*_partial.aprt" EXCLUDE)
install(DIRECTORY data/demo_drive DESTINATION ${APRT_INSTALL_DATADIR}/data COMPONENT runtime)
install(FILES config/aprt.yaml DESTINATION ${CMAKE_INSTALL_FULL_SYSCONFDIR}/aprt
        COMPONENT runtime)
install(FILES config/aprt.service DESTINATION lib/systemd/system COMPONENT runtime)
install(FILES README.md docs/configuration.md docs/outputs.md
        DESTINATION ${CMAKE_INSTALL_DOCDIR} COMPONENT runtime)

# The engine for other CMake projects: static libraries, the headers their
# public headers reach, an exported target set and a version file.
set_target_properties(aprt_engine PROPERTIES EXPORT_NAME engine)
set_target_properties(aprt_kernels PROPERTIES EXPORT_NAME kernels)
set_target_properties(aprt_base PROPERTIES EXPORT_NAME base)
install(TARGETS aprt_engine aprt_kernels aprt_base EXPORT aprtTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev)
foreach(dir runtime/base runtime/engine runtime/pose kernels)
  install(DIRECTORY ${dir}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/aprt/${dir} COMPONENT dev
          FILES_MATCHING PATTERN "*.h")
endforeach()
install(EXPORT aprtTargets NAMESPACE aprt:: DESTINATION ${APRT_INSTALL_CMAKEDIR} COMPONENT dev)
configure_package_config_file(cmake/aprtConfig.cmake.in ${CMAKE_BINARY_DIR}/aprtConfig.cmake
                              INSTALL_DESTINATION ${APRT_INSTALL_CMAKEDIR}
                              PATH_VARS APRT_INSTALL_DATADIR)
write_basic_package_version_file(${CMAKE_BINARY_DIR}/aprtConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_BINARY_DIR}/aprtConfig.cmake ${CMAKE_BINARY_DIR}/aprtConfigVersion.cmake
        DESTINATION ${APRT_INSTALL_CMAKEDIR} COMPONENT dev)
add_library(aprt::engine ALIAS aprt_engine)

# --- .deb ---------------------------------------------------------------------
if(CMAKE_SYSTEM_PROCESSOR MATCHES "aarch64|arm64")
  set(APRT_DEB_ARCH arm64)
elseif(CMAKE_SYSTEM_PROCESSOR MATCHES "x86_64|AMD64")
  set(APRT_DEB_ARCH amd64)
else()
  set(APRT_DEB_ARCH ${CMAKE_SYSTEM_PROCESSOR})
endif()
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME aprt)
set(CPACK_PACKAGE_VENDOR "aprt")
set(CPACK_PACKAGE_CONTACT "aprt maintainers <aprt@localhost>")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "APR-Transformer runtime: camera frame in, global 6-DoF pose out")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_STRIP_FILES ON)  # debug information stays in the build tree
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_COMPONENTS_ALL runtime dev)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE ${APRT_DEB_ARCH})
set(CPACK_DEBIAN_PACKAGE_SECTION misc)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_NAME aprt)
set(CPACK_DEBIAN_DEV_PACKAGE_NAME aprt-dev)
set(CPACK_DEBIAN_DEV_PACKAGE_SECTION libdevel)
# Written out rather than found by dpkg-shlibdeps, which cannot see the
# unpacked arm64 sysroot of a cross build. The Debian 12 names. A cross build
# links its target libraries statically (tools/aarch64_sysroot.sh).
set(APRT_DEB_DEPENDS "libc6 (>= 2.36), libstdc++6 (>= 12), libgcc-s1, adduser")
if(NOT CMAKE_CROSSCOMPILING)
  string(APPEND APRT_DEB_DEPENDS ", libyaml-0-2")
  if(APRT_HAVE_IMAGE_CODECS)
    string(APPEND APRT_DEB_DEPENDS ", libpng16-16, libjpeg62-turbo")
  endif()
  if(APRT_HAVE_SODIUM)
    string(APPEND APRT_DEB_DEPENDS ", libsodium23")
  endif()
  if(APRT_HAVE_DDS)
    string(APPEND APRT_DEB_DEPENDS ", libddsc0debian (>= 0.10)")
  endif()
  if(APRT_HAVE_LIBCAMERA)
    string(APPEND APRT_DEB_DEPENDS ", libcamera0.0.3")
  endif()
endif()
set(CPACK_DEBIAN_RUNTIME_PACKAGE_DEPENDS "${APRT_DEB_DEPENDS}")
set(CPACK_DEBIAN_RUNTIME_PACKAGE_SUGGESTS "can-utils")
set(CPACK_DEBIAN_DEV_PACKAGE_DEPENDS "aprt (= ${PROJECT_VERSION})")
set(CPACK_DEBIAN_RUNTIME_PACKAGE_CONTROL_EXTRA
    ${PROJECT_SOURCE_DIR}/config/debian/conffiles ${PROJECT_SOURCE_DIR}/config/debian/postinst
    ${PROJECT_SOURCE_DIR}/config/debian/postrm)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_CONTROL_STRICT_PERMISSION ON)
include(CPack)
