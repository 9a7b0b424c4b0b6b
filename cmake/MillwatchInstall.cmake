# `cmake --install` and the Debian package (CPack): the programs, the example configurations,
# the LCM type definitions and lcm-spy's jar, the README, and millwatchd as a systemd service
# (unit, sysusers.d entry for its user, its configuration under <sysconfdir>/millwatch/).
#
#   cmake --install build/release                 # /usr/local; config in /usr/local/etc/millwatch
#   cpack --config build/release/CPackConfig.cmake # millwatch_<version>_<arch>.deb, prefix /usr,
#                                                  # config /etc/millwatch/millwatchd.json
include(GNUInstallDirs)

install(TARGETS millwatch millwatchd RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/config/
        DESTINATION ${CMAKE_INSTALL_DATADIR}/millwatch/config)
file(GLOB MILLWATCH_LCM_DEFINITIONS ${PROJECT_SOURCE_DIR}/msgs/*.lcm)
install(FILES ${MILLWATCH_LCM_DEFINITIONS} DESTINATION ${CMAKE_INSTALL_DATADIR}/millwatch/lcmtypes)
if(TARGET millwatch_types)
  install(FILES ${PROJECT_BINARY_DIR}/millwatch_types.jar DESTINATION ${CMAKE_INSTALL_DATADIR}/java)
endif()
install(FILES ${PROJECT_SOURCE_DIR}/README.md DESTINATION ${CMAKE_INSTALL_DOCDIR})
install(FILES ${PROJECT_SOURCE_DIR}/packaging/millwatch.sysusers
        DESTINATION lib/sysusers.d RENAME millwatch.conf)
# The unit names the installed paths, so it is written at install time for the prefix then in
# force (the package's /usr, or --prefix): /usr puts the configuration in /etc.
install(CODE "set(MW_SOURCE_DIR \"${PROJECT_SOURCE_DIR}\")
set(MW_BINARY_DIR \"${PROJECT_BINARY_DIR}\")")
install(SCRIPT ${PROJECT_SOURCE_DIR}/cmake/MillwatchInstallService.cmake)

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME millwatch)
set(CPACK_PACKAGE_VENDOR "millwatch")
set(CPACK_PACKAGE_CONTACT "millwatch maintainers <millwatch@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${PROJECT_DESCRIPTION}")
set(CPACK_PACKAGE_DESCRIPTION
    "millwatch monitors micro-milling from dynamometer forces: spindle speed, tooth periods, phase angle, per-flute peaks, a mechanistic model in lockstep and tool-state alerts, published on LCM. millwatchd runs beside the machine (systemd service); millwatch replays, simulates and publishes recorded cuts.")
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_DEPENDS "systemd")
if(MILLWATCH_MATIO_PACKAGE)  # loaded with dlopen (shell/matio_library.hpp): not in shlibdeps
  string(APPEND CPACK_DEBIAN_PACKAGE_DEPENDS ", ${MILLWATCH_MATIO_PACKAGE}")
endif()
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "gnuplot-nox, liblcm-bin, liblcm-java")  # plots; lcm-logger, lcm-spy
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA
    ${PROJECT_SOURCE_DIR}/packaging/postinst ${PROJECT_SOURCE_DIR}/packaging/prerm
    ${PROJECT_SOURCE_DIR}/packaging/postrm ${PROJECT_SOURCE_DIR}/packaging/conffiles)
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
set(CPACK_SET_DESTDIR ON)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_INSTALL_PREFIX /usr)
include(CPack)
