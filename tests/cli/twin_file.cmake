# The twin file and the labels file name bad input by file and field (docs/twin-file.md): a key the
# format does not have, a labels file that is empty or names no known fault; a version-1 twin still
# loads, with one warning; a twin that cannot be written is an error, not exit code 0
set(d ${PROJECT_BINARY_DIR}/cli-pipeline)
set(s ${PROJECT_SOURCE_DIR}/tests/data/cli)
# (only where /dev/full is the device: where it is missing, identify would create a file there)
execute_process(COMMAND test -c /dev/full RESULT_VARIABLE no_dev_full)
if(no_dev_full EQUAL 0)
  add_test(NAME cli.identify_disk_full COMMAND twinwatch identify ${d}/exc.csv -o /dev/full)
  set_tests_properties(cli.identify_disk_full PROPERTIES FIXTURES_REQUIRED recordings
                       PASS_REGULAR_EXPRESSION "error: /dev/full: cannot write the twin file: No space left on device")
endif()
# a twin written by an earlier twinwatch (version 1) and one with a misspelt monitor key
add_test(NAME cli.twin_version1_setup COMMAND ${CMAKE_COMMAND} -Din=${d}/twin.json -Dout=${d}/twin_v1.json
         "-Dfrom=\"version\": 2" "-Dto=\"version\": 1" -P ${s}/edit_file.cmake)
add_test(NAME cli.twin_bad_monitor_setup COMMAND ${CMAKE_COMMAND} -Din=${d}/twin.json -Dout=${d}/twin_bad_monitor.json
         "-Dfrom=\"raise_after\"" "-Dto=\"raise_aftr\"" -P ${s}/edit_file.cmake)
set_tests_properties(cli.twin_version1_setup cli.twin_bad_monitor_setup PROPERTIES FIXTURES_REQUIRED twin FIXTURES_SETUP edited_twins)
add_test(NAME cli.validate_version1_twin COMMAND twinwatch validate --twin ${d}/twin_v1.json ${d}/fig.csv --payload-mass 0.5 --payload-com 0 0 0.04)
set_tests_properties(cli.validate_version1_twin PROPERTIES FIXTURES_REQUIRED "recordings;edited_twins"
                     PASS_REGULAR_EXPRESSION "\\[warning\\] [^\n]*twin_v1.json: a version-1 twin file, read as version 2 with every field present[^\n]*\n.*J6")
add_test(NAME cli.validate_bad_monitor_key COMMAND twinwatch validate --twin ${d}/twin_bad_monitor.json ${d}/fig.csv)
set_tests_properties(cli.validate_bad_monitor_key PROPERTIES FIXTURES_REQUIRED "recordings;edited_twins"
                     PASS_REGULAR_EXPRESSION "error: [^\n]*twin_bad_monitor.json: field 'monitor.raise_aftr': unknown key, expected one of: static_level_A")
# report --labels: the labels simulate wrote load; a bad or empty labels file is named
add_test(NAME cli.report_labels COMMAND twinwatch report --twin ${d}/twin.json ${d}/fig.csv --payload-mass 0.5 -o ${d}/report_labels.html
         --labels ${d}/fig.labels.json)
set_tests_properties(cli.report_labels PROPERTIES FIXTURES_REQUIRED "recordings;twin" PASS_REGULAR_EXPRESSION "report written")
add_test(NAME cli.report_bad_labels COMMAND twinwatch report --twin ${d}/twin.json ${d}/fig.csv -o ${d}/report_bad.html
         --labels ${s}/meteor.labels.json)
set_tests_properties(cli.report_bad_labels PROPERTIES FIXTURES_REQUIRED "recordings;twin"
                     PASS_REGULAR_EXPRESSION "error: [^\n]*meteor.labels.json: field 'faults\\[0\\].type': expected one of resistance, [^\n]*got \"meteor\"")
add_test(NAME cli.report_empty_labels COMMAND twinwatch report --twin ${d}/twin.json ${d}/fig.csv -o ${d}/report_empty.html
         --labels ${s}/empty.labels.json)
set_tests_properties(cli.report_empty_labels PROPERTIES FIXTURES_REQUIRED "recordings;twin"
                     PASS_REGULAR_EXPRESSION "error: [^\n]*empty.labels.json: the file is empty")
