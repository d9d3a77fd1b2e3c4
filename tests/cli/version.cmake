add_test(NAME cli.version COMMAND twinwatch --version)
set_tests_properties(cli.version PROPERTIES PASS_REGULAR_EXPRESSION "twinwatch [0-9]+\\.[0-9]+\\.[0-9]+")
add_test(NAME cli.help_lists_verbs COMMAND twinwatch --help)
set_tests_properties(cli.help_lists_verbs PROPERTIES PASS_REGULAR_EXPRESSION "Subcommands:")
