# The Debian package: `cpack -G DEB` in a build directory configured with
# CMAKE_INSTALL_PREFIX=/usr (the presets do) gives liftd_<version>_<arch>.deb there, with
# liftd, liftctl, dcp-drive-sim, their man pages (from --help), the units, sysusers.d and
# tmpfiles.d files, the journal catalog, /etc/liftd/liftd.json as a conffile and the example
# configurations. Maintainer scripts: cmake/deb/.

# Man pages, generated from each program's --help at build time.
set(liftd_man_pages "")
foreach(page "liftd;8;lift controller master daemon (DCP drive link, travels, JSON API)"
             "liftctl;1;command-line client of the liftd JSON API")
  list(GET page 0 name)
  list(GET page 1 section)
  list(GET page 2 summary)
  set(out ${CMAKE_BINARY_DIR}/man/${name}.${section}.gz)
  add_custom_command(
    OUTPUT ${out}
    COMMAND ${CMAKE_COMMAND} -DPROGRAM=$<TARGET_FILE:${name}> -DNAME=${name} -DSECTION=${section}
            -DVERSION=${PROJECT_VERSION} "-DSUMMARY=${summary}" -DOUT=${out}
            -P ${PROJECT_SOURCE_DIR}/cmake/HelpToMan.cmake
    DEPENDS ${name} ${PROJECT_SOURCE_DIR}/cmake/HelpToMan.cmake
    COMMENT "Man page ${name}(${section}) from ${name} --help"
    VERBATIM)
  install(FILES ${out} DESTINATION ${CMAKE_INSTALL_MANDIR}/man${section})
  list(APPEND liftd_man_pages ${out})
endforeach()
add_custom_target(man_pages ALL DEPENDS ${liftd_man_pages})

install(FILES config/liftd.json DESTINATION ${CMAKE_INSTALL_FULL_SYSCONFDIR}/liftd)
install(DIRECTORY config/ DESTINATION ${CMAKE_INSTALL_DOCDIR}/examples FILES_MATCHING PATTERN "*.json")

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME liftd)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${PROJECT_DESCRIPTION}")
set(CPACK_PACKAGE_CONTACT "liftd maintainers <liftd@localhost>")
set(CPACK_PACKAGING_INSTALL_PREFIX ${CMAKE_INSTALL_PREFIX})
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION misc)
# Shared-library dependencies (libspdlog, libfmt, libsystemd, libstdc++) from dpkg-shlibdeps.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# systemd-sysusers, systemd-tmpfiles and the units; deb-systemd-helper for enable/start.
set(CPACK_DEBIAN_PACKAGE_DEPENDS "systemd, init-system-helpers")
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA
    ${PROJECT_SOURCE_DIR}/cmake/deb/conffiles ${PROJECT_SOURCE_DIR}/cmake/deb/postinst
    ${PROJECT_SOURCE_DIR}/cmake/deb/prerm ${PROJECT_SOURCE_DIR}/cmake/deb/postrm)
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
set(CPACK_STRIP_FILES ON)
include(CPack)
