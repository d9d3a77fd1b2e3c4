add_test(NAME cli.version COMMAND twinwatch --version)
set_tests_properties(cli.version PROPERTIES PASS_REGULAR_EXPRESSION "twinwatch [0-9]+\\.[0-9]+\\.[0-9]+")
add_test(NAME cli.help_lists_verbs COMMAND twinwatch --help)
set_tests_properties(cli.help_lists_verbs PROPERTIES PASS_REGULAR_EXPRESSION "Subcommands:")
# every verb's --help ends with the exit statuses (a verb's own footer replaced the inherited one:
# events, excite, friction-study and identify-torque said none before session 39)
add_test(NAME cli.every_verbs_help_says_its_exit_status
  COMMAND sh -c "tw=$<TARGET_FILE:twinwatch>; n=0; \
for v in $($tw --help | sed -n '/^Subcommands:/,$p' | sed -n 's/^  \\([a-z][a-z-]*\\) .*/\\1/p'); do n=$((n+1)); \
$tw $v --help | tail -n 3 | grep -q '^Exit status: 0 success' || echo missing: $v; done; echo checked $n verbs")
set_tests_properties(cli.every_verbs_help_says_its_exit_status PROPERTIES
  PASS_REGULAR_EXPRESSION "checked (1[5-9]|2[0-9]) verbs" FAIL_REGULAR_EXPRESSION "missing:")
