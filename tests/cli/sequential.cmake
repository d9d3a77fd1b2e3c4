# identify --method sequential (Cao): quasi-static + sine + general recording -> twin -> validate
set(d ${PROJECT_BINARY_DIR}/cli-sequential)
file(MAKE_DIRECTORY ${d})
set(v ${PROJECT_SOURCE_DIR}/scenarios/ur3e/validation)
add_test(NAME cli.sequential_simulate_qs COMMAND twinwatch simulate ${v}/quasi_static_train.yaml --duration 92 -o ${d}/qs.csv -q)
add_test(NAME cli.sequential_simulate_sine COMMAND twinwatch simulate ${v}/sine_train.yaml --duration 20 -o ${d}/sine.csv -q)
add_test(NAME cli.sequential_simulate_exc COMMAND twinwatch simulate ${v}/excitation_train.yaml --duration 30 -o ${d}/exc.csv -q)
set_tests_properties(cli.sequential_simulate_qs cli.sequential_simulate_sine cli.sequential_simulate_exc PROPERTIES FIXTURES_SETUP seq_recordings)
add_test(NAME cli.identify_sequential COMMAND twinwatch identify --method sequential --quasi-static ${d}/qs.csv --sine ${d}/sine.csv
         ${d}/exc.csv --lasso-joints 3 -o ${d}/twin.json)
set_tests_properties(cli.identify_sequential PROPERTIES FIXTURES_REQUIRED seq_recordings FIXTURES_SETUP seq_twin
                     PASS_REGULAR_EXPRESSION "gravity from 12 paired poses. Lasso on 135 candidates")
add_test(NAME cli.validate_sequential COMMAND twinwatch validate --twin ${d}/twin.json ${d}/sine.csv --json)
set_tests_properties(cli.validate_sequential PROPERTIES FIXTURES_REQUIRED seq_twin PASS_REGULAR_EXPRESSION "\"joints\":\\[\\{\"d_tau_pct\"")
add_test(NAME cli.identify_sequential_needs_sine COMMAND twinwatch identify --method sequential --quasi-static ${d}/qs.csv ${d}/exc.csv
         -o ${d}/never.json)
set_tests_properties(cli.identify_sequential_needs_sine PROPERTIES FIXTURES_REQUIRED seq_recordings
                     PASS_REGULAR_EXPRESSION "--method sequential needs --sine FILE")
add_test(NAME cli.identify_sequential_needs_quasi_static COMMAND twinwatch identify --method sequential --sine ${d}/sine.csv ${d}/exc.csv
         -o ${d}/never.json)
set_tests_properties(cli.identify_sequential_needs_quasi_static PROPERTIES FIXTURES_REQUIRED seq_recordings
                     PASS_REGULAR_EXPRESSION "--method sequential needs --quasi-static FILE")
