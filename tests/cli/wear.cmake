# evaluate's collision sweep and scenario arguments: validation errors name the field and value
# (the sweep itself trains a twin first and runs from the CLI for docs/validation.md).
add_test(NAME cli.evaluate_sweep_bad_link COMMAND twinwatch evaluate --sweep-collisions --links 2 9)
set_tests_properties(cli.evaluate_sweep_bad_link PROPERTIES PASS_REGULAR_EXPRESSION "sweep link 9 is out of range, expected 1..6")
add_test(NAME cli.evaluate_sweep_bad_magnitude COMMAND twinwatch evaluate --sweep-collisions --magnitudes 5 -1)
set_tests_properties(cli.evaluate_sweep_bad_magnitude PROPERTIES PASS_REGULAR_EXPRESSION "sweep magnitude -1 N·m, must be > 0")
add_test(NAME cli.evaluate_no_scenarios COMMAND twinwatch evaluate)
set_tests_properties(cli.evaluate_no_scenarios PROPERTIES PASS_REGULAR_EXPRESSION "give a SCENARIOS directory or file, or --sweep-collisions")
