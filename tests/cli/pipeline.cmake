# simulate -> identify -> validate -> monitor -> report, on short runs (fixtures keep the order)
set(d ${PROJECT_BINARY_DIR}/cli-pipeline)
file(MAKE_DIRECTORY ${d})
set(s ${PROJECT_SOURCE_DIR}/tests/data/cli)
add_test(NAME cli.simulate_exc COMMAND twinwatch simulate ${s}/short_exc.yaml -o ${d}/exc.csv)
add_test(NAME cli.simulate_fig COMMAND twinwatch simulate ${s}/short_fig8.yaml -o ${d}/fig.csv)
set_tests_properties(cli.simulate_exc cli.simulate_fig PROPERTIES FIXTURES_SETUP recordings PASS_REGULAR_EXPRESSION "samples")
add_test(NAME cli.identify COMMAND twinwatch identify ${d}/exc.csv ${d}/fig.csv --known-payload ${d}/fig.csv=0.5,0,0,0.04 -o ${d}/twin.json)
set_tests_properties(cli.identify PROPERTIES FIXTURES_REQUIRED recordings FIXTURES_SETUP twin PASS_REGULAR_EXPRESSION "J6")
add_test(NAME cli.validate_json COMMAND twinwatch validate --twin ${d}/twin.json ${d}/fig.csv --payload-mass 0.5 --payload-com 0 0 0.04 --json)
set_tests_properties(cli.validate_json PROPERTIES FIXTURES_REQUIRED twin PASS_REGULAR_EXPRESSION "\"joints\":\\[\\{\"d_tau_pct\"")
add_test(NAME cli.monitor_healthy COMMAND twinwatch monitor --twin ${d}/twin.json ${d}/fig.csv --payload-mass 0.5 --payload-com 0 0 0.04 --db ${d}/events.db)
set_tests_properties(cli.monitor_healthy PROPERTIES FIXTURES_REQUIRED twin PASS_REGULAR_EXPRESSION "samples, 0 gap\\(s\\)")
add_test(NAME cli.report COMMAND twinwatch report --twin ${d}/twin.json ${d}/fig.csv --payload-mass 0.5 -o ${d}/report.html)
set_tests_properties(cli.report PROPERTIES FIXTURES_REQUIRED twin PASS_REGULAR_EXPRESSION "report written")
add_test(NAME cli.simulate_bad_field COMMAND twinwatch simulate ${s}/bad_field.yaml -o ${d}/bad.csv)
set_tests_properties(cli.simulate_bad_field PROPERTIES PASS_REGULAR_EXPRESSION "bad_field.yaml:2: field 'duration': expected a number, got 'fast'")
add_test(NAME cli.validate_missing_file COMMAND twinwatch validate --twin ${d}/nonexistent.json ${d}/fig.csv)
set_tests_properties(cli.validate_missing_file PROPERTIES WILL_FAIL TRUE)
# the back-driven factor fitted jointly with the rest: J2-J4 get a c_gen below 1 and the table
# shows their back-driven share; a bad value of the option is named
add_test(NAME cli.identify_efficiency_joint COMMAND twinwatch identify ${d}/exc.csv ${d}/fig.csv --known-payload ${d}/fig.csv=0.5,0,0,0.04
         --efficiency-fit joint -o ${d}/twin_joint.json)
set_tests_properties(cli.identify_efficiency_joint PROPERTIES FIXTURES_REQUIRED recordings
                     PASS_REGULAR_EXPRESSION "J2 +[0-9]+ +[0-9.]+ +[0-9.]+ +0\\.[0-9]+ +[0-9]+\\.[0-9]")
add_test(NAME cli.identify_efficiency_bad COMMAND twinwatch identify ${d}/exc.csv --efficiency-fit sometimes -o ${d}/twin_bad.json)
set_tests_properties(cli.identify_efficiency_bad PROPERTIES FIXTURES_REQUIRED recordings
                     PASS_REGULAR_EXPRESSION "--efficiency-fit sometimes: expected joint or alternating")
# --efficiency-passes: a negative count is refused with the field and value
add_test(NAME cli.identify_bad_efficiency_passes COMMAND twinwatch identify ${d}/exc.csv --efficiency-passes -1 -o ${d}/bad.json)
set_tests_properties(cli.identify_bad_efficiency_passes PROPERTIES FIXTURES_REQUIRED recordings PASS_REGULAR_EXPRESSION "efficiency_passes is -1, must be >= 0")
# --progress shows the bar on a pipe too (ctest's is not a terminal)
add_test(NAME cli.identify_progress COMMAND twinwatch identify ${d}/exc.csv --progress -o ${d}/twin_progress.json)
set_tests_properties(cli.identify_progress PROPERTIES FIXTURES_REQUIRED recordings PASS_REGULAR_EXPRESSION "identifying +[0-9]+ %")
# --column-map is for recordings: a live RTDE stream carries the controller's own names
add_test(NAME cli.monitor_rtde_column_map COMMAND twinwatch monitor --twin ${d}/twin.json --rtde 127.0.0.1:1
         --column-map ${PROJECT_SOURCE_DIR}/data/column_maps/kinova_gen3_chiha.csv --db "")
set_tests_properties(cli.monitor_rtde_column_map PROPERTIES FIXTURES_REQUIRED twin
                     PASS_REGULAR_EXPRESSION "--column-map applies to a RECORDING")
