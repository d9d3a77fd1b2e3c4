# identify --method mlp|hybrid on the pipeline's short recordings (fixture "recordings" from
# pipeline.cmake), then validate and monitor with the learned twins
set(d ${PROJECT_BINARY_DIR}/cli-pipeline)
add_test(NAME cli.identify_hybrid COMMAND twinwatch identify ${d}/exc.csv ${d}/fig.csv --known-payload ${d}/fig.csv=0.5,0,0,0.04
         --method hybrid --seed 3 --max-evaluations 300 -o ${d}/twin_hybrid.json)
set_tests_properties(cli.identify_hybrid PROPERTIES FIXTURES_REQUIRED recordings FIXTURES_SETUP twin_hybrid
                     PASS_REGULAR_EXPRESSION "\\(hybrid method\\).*network: inputs qd\\+friction_shape \\(18\\), hidden 15, l2 0.01, seed 3")
add_test(NAME cli.identify_mlp COMMAND twinwatch identify ${d}/exc.csv ${d}/fig.csv --known-payload ${d}/fig.csv=0.5,0,0,0.04
         --method mlp --hidden 10 --l2 1e-3 --max-evaluations 200 -o ${d}/twin_mlp.json)
set_tests_properties(cli.identify_mlp PROPERTIES FIXTURES_REQUIRED recordings FIXTURES_SETUP twin_mlp
                     PASS_REGULAR_EXPRESSION "\\(mlp method\\).*network: inputs q\\+qd \\(12\\), hidden 10, l2 0.001")
add_test(NAME cli.validate_hybrid COMMAND twinwatch validate --twin ${d}/twin_hybrid.json ${d}/fig.csv --payload-mass 0.5 --payload-com 0 0 0.04 --json)
set_tests_properties(cli.validate_hybrid PROPERTIES FIXTURES_REQUIRED twin_hybrid PASS_REGULAR_EXPRESSION "\"joints\":\\[\\{\"d_tau_pct\"")
add_test(NAME cli.monitor_hybrid COMMAND twinwatch monitor --twin ${d}/twin_hybrid.json ${d}/fig.csv --payload-mass 0.5 --payload-com 0 0 0.04 --db "")
set_tests_properties(cli.monitor_hybrid PROPERTIES FIXTURES_REQUIRED twin_hybrid PASS_REGULAR_EXPRESSION "samples, 0 gap\\(s\\), 0 event\\(s\\)")
add_test(NAME cli.monitor_mlp COMMAND twinwatch monitor --twin ${d}/twin_mlp.json ${d}/fig.csv --payload-mass 0.5 --payload-com 0 0 0.04 --db "")
set_tests_properties(cli.monitor_mlp PROPERTIES FIXTURES_REQUIRED twin_mlp PASS_REGULAR_EXPRESSION "samples, 0 gap\\(s\\)")
add_test(NAME cli.identify_learned_options_need_a_learned_method COMMAND twinwatch identify ${d}/exc.csv --hidden 20 -o ${d}/never.json)
set_tests_properties(cli.identify_learned_options_need_a_learned_method PROPERTIES FIXTURES_REQUIRED recordings
                     PASS_REGULAR_EXPRESSION "--hidden applies only to --method mlp or hybrid, not physics")
add_test(NAME cli.identify_unknown_method COMMAND twinwatch identify ${d}/exc.csv --method lstm -o ${d}/never.json)
set_tests_properties(cli.identify_unknown_method PROPERTIES FIXTURES_REQUIRED recordings
                     PASS_REGULAR_EXPRESSION "--method lstm: expected physics, sequential, mlp or hybrid")
add_test(NAME cli.identify_unknown_feature COMMAND twinwatch identify ${d}/exc.csv --method hybrid --inputs qd+jerk -o ${d}/never.json)
set_tests_properties(cli.identify_unknown_feature PROPERTIES FIXTURES_REQUIRED recordings PASS_REGULAR_EXPRESSION "unknown feature 'jerk'")
