# align: two simulated runs of one motion, the second recording started 0.7 s late into it (the
# RTDE start-trigger latency of UR3e §3.4), aligned by cross-correlation (UR3e Table 2 layout)
set(da ${PROJECT_BINARY_DIR}/cli-align)
file(MAKE_DIRECTORY ${da})
add_test(NAME cli.align_setup
  COMMAND sh -c "$<TARGET_FILE:twinwatch> simulate ${PROJECT_SOURCE_DIR}/tests/data/cli/short_fig8.yaml --seed 6 -o ${da}/full.csv -q && \
(head -n 1 ${da}/full.csv; tail -n +352 ${da}/full.csv) > ${da}/late.csv && echo CUT")
set_tests_properties(cli.align_setup PROPERTIES FIXTURES_SETUP align_pair PASS_REGULAR_EXPRESSION "CUT")
# a recording against its own first rows is in step (a lag of -0.00 samples was called "early"); the
# headings of rad/s^2 stand apart (they ran together: audit of session 56)
add_test(NAME cli.align_in_step_and_wide_headings
  COMMAND sh -c "head -n 3001 ${da}/full.csv > ${da}/head.csv && $<TARGET_FILE:twinwatch> align ${da}/full.csv ${da}/head.csv --signal target_qdd")
set_tests_properties(cli.align_in_step_and_wide_headings PROPERTIES FIXTURES_REQUIRED align_pair
  PASS_REGULAR_EXPRESSION "common lag 0\\.00 samples = 0\\.0 ms \\([^\n]*head\\.csv is in step\\)\nJoint +lag \\[ms\\] +corr +Raw RMSE \\[rad/s\\^2\\] +Aligned RMSE")
# joint angles: the 350 dropped rows come back as a lag of -350 samples (the second one is early)
add_test(NAME cli.align_angles COMMAND twinwatch align ${PROJECT_BINARY_DIR}/cli-pipeline/fig.csv ${da}/late.csv)
set_tests_properties(cli.align_angles PROPERTIES FIXTURES_REQUIRED "recordings;align_pair"
  PASS_REGULAR_EXPRESSION "common lag -350\\.00 samples = -700\\.0 ms.*Raw RMSE \\[rad\\] +Aligned RMSE \\[rad\\].*J6 +-700\\.0")
# noisy currents (different noise seeds), per joint, as JSON
add_test(NAME cli.align_currents_json
  COMMAND twinwatch align ${PROJECT_BINARY_DIR}/cli-pipeline/fig.csv ${da}/late.csv --signal actual_current --per-joint --json)
set_tests_properties(cli.align_currents_json PROPERTIES FIXTURES_REQUIRED "recordings;align_pair"
  PASS_REGULAR_EXPRESSION "\"joint\":2,\"lag_ms\":-70[01]\\.[0-9]+,\"lag_samples\":-350\\.[0-9]+")
add_test(NAME cli.align_window_edge COMMAND twinwatch align ${PROJECT_BINARY_DIR}/cli-pipeline/fig.csv ${da}/late.csv --max-lag-ms 500)
set_tests_properties(cli.align_window_edge PROPERTIES FIXTURES_REQUIRED "recordings;align_pair"
  PASS_REGULAR_EXPRESSION "peak lies on the edge of the \\+-500 ms search window")
add_test(NAME cli.align_bad_signal COMMAND twinwatch align ${PROJECT_BINARY_DIR}/cli-pipeline/fig.csv ${da}/late.csv --signal qdd)
set_tests_properties(cli.align_bad_signal PROPERTIES FIXTURES_REQUIRED "recordings;align_pair"
  PASS_REGULAR_EXPRESSION "--signal 'qdd' is not a recording column group. expected one of actual_q")
add_test(NAME cli.align_bad_signal_fails COMMAND twinwatch align ${PROJECT_BINARY_DIR}/cli-pipeline/fig.csv ${da}/late.csv --signal qdd)
set_tests_properties(cli.align_bad_signal_fails PROPERTIES FIXTURES_REQUIRED "recordings;align_pair" WILL_FAIL TRUE)
# the monitor with Cao's FIR on the residuals (thresholds learned with the IIR: a note says so)
add_test(NAME cli.monitor_fir COMMAND twinwatch monitor --twin ${PROJECT_BINARY_DIR}/cli-pipeline/twin.json
  ${PROJECT_BINARY_DIR}/cli-pipeline/fig.csv --payload-mass 0.5 --payload-com 0 0 0.04 --db "" --filter fir)
set_tests_properties(cli.monitor_fir PROPERTIES FIXTURES_REQUIRED twin
  PASS_REGULAR_EXPRESSION "learned with residual filter 'iir'.*samples, 0 gap\\(s\\)")
add_test(NAME cli.monitor_bad_filter COMMAND twinwatch monitor --twin ${PROJECT_BINARY_DIR}/cli-pipeline/twin.json
  ${PROJECT_BINARY_DIR}/cli-pipeline/fig.csv --db "" --filter iir,fir)
set_tests_properties(cli.monitor_bad_filter PROPERTIES FIXTURES_REQUIRED twin
  PASS_REGULAR_EXPRESSION "residual_filter \\(--filter\\) has 2 entries, expected 0, 1 or 6")
# thresholds re-learned with the FIR, then monitored with it: no mismatch note, no alarm
add_test(NAME cli.thresholds_fir
  COMMAND sh -c "cp ${PROJECT_BINARY_DIR}/cli-pipeline/twin.json ${da}/twin_fir.json && \
$<TARGET_FILE:twinwatch> thresholds --twin ${da}/twin_fir.json ${PROJECT_BINARY_DIR}/cli-pipeline/fig.csv --payload-mass 0.5 --filter fir && \
$<TARGET_FILE:twinwatch> monitor --twin ${da}/twin_fir.json ${PROJECT_BINARY_DIR}/cli-pipeline/fig.csv --payload-mass 0.5 --payload-com 0 0 0.04 --db '' --filter fir 2>&1")
set_tests_properties(cli.thresholds_fir PROPERTIES FIXTURES_REQUIRED twin
  PASS_REGULAR_EXPRESSION "with residual filter 'fir' and stored in.*5000 samples, 0 gap\\(s\\), 0 event\\(s\\)"
  FAIL_REGULAR_EXPRESSION "note: the thresholds")
# the observer's debounce per joint, chosen on a healthy recording the thresholds were not learned on
# (another seed of the same program and payload), stored, and used by the monitor without an alarm
add_test(NAME cli.thresholds_debounce_validation
  COMMAND sh -c "cp ${PROJECT_BINARY_DIR}/cli-pipeline/twin.json ${da}/twin_deb.json && \
$<TARGET_FILE:twinwatch> thresholds --twin ${da}/twin_deb.json ${PROJECT_BINARY_DIR}/cli-pipeline/fig.csv --payload-mass 0.5 --debounce-validation ${da}/full.csv && \
$<TARGET_FILE:twinwatch> monitor --twin ${da}/twin_deb.json ${da}/full.csv --payload-mass 0.5 --payload-com 0 0 0.04 --db '' 2>&1")
set_tests_properties(cli.thresholds_debounce_validation PROPERTIES FIXTURES_REQUIRED "twin;align_pair"
  PASS_REGULAR_EXPRESSION "observer debounce per joint ([12] )*1( [12])* \\(samples\\), chosen on 1 validation recording\\(s\\), 10 s.*observer debounce per joint: [12] [12] [12] [12] [12] [12] sample\\(s\\) \\(chosen on healthy validation runs.*5000 samples, 0 gap\\(s\\), 0 event\\(s\\)")
# a validation recording that is also a training recording is refused (the choice would be in-sample)
add_test(NAME cli.thresholds_debounce_validation_in_sample
  COMMAND sh -c "cp ${PROJECT_BINARY_DIR}/cli-pipeline/twin.json ${da}/twin_ins.json && \
$<TARGET_FILE:twinwatch> thresholds --twin ${da}/twin_ins.json ${PROJECT_BINARY_DIR}/cli-pipeline/fig.csv --payload-mass 0.5 \
--debounce-validation ${PROJECT_BINARY_DIR}/cli-pipeline/../cli-pipeline/fig.csv 2>&1; echo exit \$?")
set_tests_properties(cli.thresholds_debounce_validation_in_sample PROPERTIES FIXTURES_REQUIRED twin
  PASS_REGULAR_EXPRESSION "fig.csv is also one of the recordings the thresholds are learned on. the choice needs healthy runs they were not learned on.*exit [1-9]")
# per-joint observer debounce chosen for the default set and for a program's set, each kept and used
add_test(NAME cli.thresholds_debounce_program
  COMMAND sh ${PROJECT_SOURCE_DIR}/tests/cli/thresholds_debounce_program.sh $<TARGET_FILE:twinwatch>
          ${PROJECT_BINARY_DIR}/cli-pipeline/twin.json ${PROJECT_BINARY_DIR}/cli-pipeline/fig.csv ${da}/full.csv ${da})
set_tests_properties(cli.thresholds_debounce_program PROPERTIES FIXTURES_REQUIRED "twin;align_pair"
  PASS_REGULAR_EXPRESSION "EACH-SET-KEEPS-ITS-OWN-COUNTS")
# a program's set leaves the default set as it was, the observer's thresholds included: the default
# set's trace (residuals, thresholds, observer thresholds per sample) is the same before and after
add_test(NAME cli.thresholds_program_keeps_the_default_set
  COMMAND sh -c "cp ${PROJECT_BINARY_DIR}/cli-pipeline/twin.json ${da}/twin_keep.json && \
$<TARGET_FILE:twinwatch> monitor --twin ${da}/twin_keep.json ${da}/full.csv --payload-mass 0.5 --db '' -q --trace ${da}/keep_before.csv && \
$<TARGET_FILE:twinwatch> thresholds --twin ${da}/twin_keep.json ${da}/full.csv --payload-mass 0.5 --program other && \
$<TARGET_FILE:twinwatch> monitor --twin ${da}/twin_keep.json ${da}/full.csv --payload-mass 0.5 --db '' -q --trace ${da}/keep_after.csv && \
$<TARGET_FILE:twinwatch> monitor --twin ${da}/twin_keep.json ${da}/full.csv --payload-mass 0.5 --db '' -q --program other --trace ${da}/keep_other.csv && \
cmp ${da}/keep_before.csv ${da}/keep_after.csv && echo DEFAULT-KEPT && (cmp -s ${da}/keep_before.csv ${da}/keep_other.csv || echo PROGRAM-DIFFERS)")
set_tests_properties(cli.thresholds_program_keeps_the_default_set PROPERTIES FIXTURES_REQUIRED "twin;align_pair"
  PASS_REGULAR_EXPRESSION "DEFAULT-KEPT.*PROGRAM-DIFFERS")
# thresholds per program: learned into a named set (with the largest load each joint reversed under,
# session 25), selected with --program; the default set stays
add_test(NAME cli.thresholds_program
  COMMAND sh -c "cp ${PROJECT_BINARY_DIR}/cli-pipeline/twin.json ${da}/twin_prog.json && \
$<TARGET_FILE:twinwatch> thresholds --twin ${da}/twin_prog.json ${PROJECT_BINARY_DIR}/cli-pipeline/fig.csv --payload-mass 0.5 --program fig8_loop && \
$<TARGET_FILE:twinwatch> monitor --twin ${da}/twin_prog.json ${PROJECT_BINARY_DIR}/cli-pipeline/fig.csv --payload-mass 0.5 --payload-com 0 0 0.04 --db '' --program fig8_loop 2>&1 && \
$<TARGET_FILE:twinwatch> monitor --twin ${da}/twin_prog.json ${PROJECT_BINARY_DIR}/cli-pipeline/fig.csv --payload-mass 0.5 --payload-com 0 0 0.04 --db '' 2>&1")
set_tests_properties(cli.thresholds_program PROPERTIES FIXTURES_REQUIRED twin
  PASS_REGULAR_EXPRESSION "thresholds of program 'fig8_loop' learned from 1 healthy recording[^\n]*\nthe largest load each joint reversed under in them \\[N[^]]*m. \\*: through the median of the identified gains, the joint's own not fixed by a known payload, as the monitor sizes faults\\], beyond which both of its thresholds widen[^\n]*: J1 [0-9]+\\.[0-9][0-9]\\*?  J2 [0-9]+\\.[0-9][0-9]  J3 .*  J6 [0-1]\\.[0-9][0-9]\\*\n.*thresholds: learned for program 'fig8_loop'.*0 event\\(s\\).*thresholds: the default set \\(.* has sets for 1 program\\(s\\). choose one with --program\\)")
add_test(NAME cli.monitor_unknown_program COMMAND twinwatch monitor --twin ${PROJECT_BINARY_DIR}/cli-pipeline/twin.json
  ${PROJECT_BINARY_DIR}/cli-pipeline/fig.csv --db "" --program palletizing)
set_tests_properties(cli.monitor_unknown_program PROPERTIES FIXTURES_REQUIRED twin
  PASS_REGULAR_EXPRESSION "no thresholds learned for program 'palletizing' \\(known: none\\)")
# monitor --trace: one row per sample (5000), residual, threshold, observer residual and observer
# threshold per joint; the thresholds are positive (the observer's too, even on the first row after
# the start-up)
add_test(NAME cli.monitor_trace
  COMMAND sh -c "$<TARGET_FILE:twinwatch> monitor --twin ${PROJECT_BINARY_DIR}/cli-pipeline/twin.json ${PROJECT_BINARY_DIR}/cli-pipeline/fig.csv \
--payload-mass 0.5 --payload-com 0 0 0.04 --db '' -q --trace ${da}/trace.csv && head -1 ${da}/trace.csv && \
echo rows $(wc -l < ${da}/trace.csv) && \
awk -F, 'NR > 1 && ($3 <= 0 || $5 <= 0) { bad++ } END { print \"non-positive thresholds:\", bad + 0 }' ${da}/trace.csv")
set_tests_properties(cli.monitor_trace PROPERTIES FIXTURES_REQUIRED twin
  PASS_REGULAR_EXPRESSION "^timestamp,residual_1_A,threshold_1_A,observer_1_Nm,observer_threshold_1_Nm,residual_2_A,[^\n]*observer_threshold_6_Nm\nrows 5001\nnon-positive thresholds: 0\n$")
# a foreign log through --column-map: thresholds, monitor and report see exactly what the RTDE columns give
add_test(NAME cli.column_map_pipeline
  COMMAND sh ${PROJECT_SOURCE_DIR}/tests/cli/column_map_pipeline.sh $<TARGET_FILE:twinwatch>
          ${PROJECT_BINARY_DIR}/cli-pipeline/twin.json ${PROJECT_BINARY_DIR}/cli-pipeline/fig.csv ${da}/full.csv
          ${PROJECT_BINARY_DIR}/cli-pipeline/collision.csv ${da})
set_tests_properties(cli.column_map_pipeline PROPERTIES FIXTURES_REQUIRED "twin;recordings;align_pair;collision_recording"
                     PASS_REGULAR_EXPRESSION "SAME-THROUGH-THE-COLUMN-MAP: [1-9]")
# every threshold set shares the twin's temperature slope, and the other sets were learned with it: a
# program's set learned on a warm-up keeps it (session 33: a 300 s pick-and-place from cold moved J2's
# slope to twice the one the default set was learned with). Two warm-ups faked on fig.csv's columns
# (22 -> 32 and 22 -> 42 degrees C): the default set learns a slope from the first; the program's set
# on the second says it keeps it, and the twin's slope is the same after it
add_test(NAME cli.thresholds_program_keeps_the_temperature_slope
  COMMAND sh -c "cp ${PROJECT_BINARY_DIR}/cli-pipeline/twin.json ${da}/twin_slope.json && \
for span in 10 20; do awk -F, -v OFS=, -v s=$span 'NR==1{for(i=1;i<=NF;i++) if($i ~ /^joint_temperatures_/) c[i]=1; print; next} {for(i in c) $i=22+s*(NR-2)/4999; print}' \
  ${PROJECT_BINARY_DIR}/cli-pipeline/fig.csv > ${da}/warm_$span.csv; done && \
$<TARGET_FILE:twinwatch> thresholds --twin ${da}/twin_slope.json ${da}/warm_10.csv --payload-mass 0.5 && \
grep -A6 '\"temperature_slope\"' ${da}/twin_slope.json > ${da}/slope_before.txt && \
$<TARGET_FILE:twinwatch> thresholds --twin ${da}/twin_slope.json ${da}/warm_20.csv --payload-mass 0.5 --program warm && \
grep -A6 '\"temperature_slope\"' ${da}/twin_slope.json > ${da}/slope_after.txt && \
test -s ${da}/slope_before.txt && cmp ${da}/slope_before.txt ${da}/slope_after.txt && echo SLOPE-KEPT")
set_tests_properties(cli.thresholds_program_keeps_the_temperature_slope PROPERTIES FIXTURES_REQUIRED twin
  PASS_REGULAR_EXPRESSION "learned on these recordings.*the twin's, which every threshold set shares.*SLOPE-KEPT")
# thresholds -q: nothing on stdout on success (the twin is still updated); without it the summary
add_test(NAME cli.thresholds_quiet
  COMMAND sh -c "cp ${PROJECT_BINARY_DIR}/cli-pipeline/twin.json ${da}/twin_q.json && \
$<TARGET_FILE:twinwatch> thresholds --twin ${da}/twin_q.json ${PROJECT_BINARY_DIR}/cli-pipeline/fig.csv --payload-mass 0.5 -q 2>/dev/null | wc -c; echo exit \$?; \
grep -c static_level ${da}/twin_q.json")
set_tests_properties(cli.thresholds_quiet PROPERTIES FIXTURES_REQUIRED twin
  PASS_REGULAR_EXPRESSION "^0\nexit 0\n[1-9]")
