# 'cmake --install' (session 21): the program and what it ships go under a prefix, and the installed
# program reads its robots and scenario library from PREFIX/share/twinwatch, not from the source tree
set(d ${PROJECT_BINARY_DIR}/cli-install)
add_test(NAME cli.install_setup COMMAND ${CMAKE_COMMAND} -E rm -rf ${d})
set_tests_properties(cli.install_setup PROPERTIES FIXTURES_SETUP install_clean)
add_test(NAME cli.install COMMAND ${CMAKE_COMMAND} --install ${PROJECT_BINARY_DIR} --prefix ${d})
set_tests_properties(cli.install PROPERTIES FIXTURES_REQUIRED install_clean FIXTURES_SETUP installed
                     PASS_REGULAR_EXPRESSION "Installing: [^\n]*/cli-install/bin/twinwatch")
add_test(NAME cli.installed_robots COMMAND ${d}/bin/twinwatch model show ur3e)
set_tests_properties(cli.installed_robots PROPERTIES FIXTURES_REQUIRED installed
                     PASS_REGULAR_EXPRESSION "robot ur3e \\(6 joints\\) from [^\n]*/cli-install/share/twinwatch/robots/ur3e.json")
add_test(NAME cli.installed_scenarios COMMAND ${d}/bin/twinwatch demo --help)
set_tests_properties(cli.installed_scenarios PROPERTIES FIXTURES_REQUIRED installed
                     PASS_REGULAR_EXPRESSION "/cli-install/share/twinwatch/scenarios/ur3e")
# $TWINWATCH_DATA_DIR still comes first, and a directory without robots is named, not skipped
add_test(NAME cli.installed_data_dir_override COMMAND ${CMAKE_COMMAND} -E env TWINWATCH_DATA_DIR=${d}/nowhere ${d}/bin/twinwatch model show ur3e)
set_tests_properties(cli.installed_data_dir_override PROPERTIES FIXTURES_REQUIRED installed
                     PASS_REGULAR_EXPRESSION "robot 'ur3e' is unknown: not a built-in robot \\(none found in [^\n]*/cli-install/nowhere/robots\\)")
# the service unit is written for the prefix given at install time and passes systemd's own check
# (an unknown key or a program that is not there fails it)
find_program(SYSTEMD_ANALYZE systemd-analyze)
if(SYSTEMD_ANALYZE)
  add_test(NAME cli.installed_service_unit
    COMMAND sh -c "cp ${d}/share/twinwatch/systemd/twinwatch-monitor@.service ${d}/twinwatch-monitor@cell3.service && \
grep -E '^(ExecStart|SuccessExitStatus)=' ${d}/twinwatch-monitor@cell3.service && ${SYSTEMD_ANALYZE} verify ${d}/twinwatch-monitor@cell3.service 2>&1 && echo VERIFIED")
  set_tests_properties(cli.installed_service_unit PROPERTIES FIXTURES_REQUIRED installed
    PASS_REGULAR_EXPRESSION "^ExecStart=[^\n]*/cli-install/bin/twinwatch monitor .TWINWATCH_ARGS\nSuccessExitStatus=4\nVERIFIED\n$")
endif()
