# Runs at install time (install(SCRIPT)): millwatchd.service for the prefix in force, and the
# daemon's configuration under its sysconfdir (/etc for the /usr prefix), kept if present.
# (file(INSTALL) puts DESTDIR before an absolute destination itself.)
if(CMAKE_INSTALL_PREFIX STREQUAL "/usr")
  set(MW_SYSCONFDIR /etc)
else()
  set(MW_SYSCONFDIR ${CMAKE_INSTALL_PREFIX}/etc)
endif()
set(MW_BINDIR ${CMAKE_INSTALL_PREFIX}/bin)
set(MW_DOCDIR ${CMAKE_INSTALL_PREFIX}/share/doc/millwatch)
configure_file(${MW_SOURCE_DIR}/packaging/millwatchd.service.in
               ${MW_BINARY_DIR}/packaging/millwatchd.service @ONLY)
file(INSTALL ${MW_BINARY_DIR}/packaging/millwatchd.service
     DESTINATION "${CMAKE_INSTALL_PREFIX}/lib/systemd/system")
if(EXISTS "$ENV{DESTDIR}${MW_SYSCONFDIR}/millwatch/millwatchd.json")
  message(STATUS "Kept: $ENV{DESTDIR}${MW_SYSCONFDIR}/millwatch/millwatchd.json")
else()
  file(INSTALL ${MW_SOURCE_DIR}/config/millwatchd.json
       DESTINATION "${MW_SYSCONFDIR}/millwatch")
endif()
