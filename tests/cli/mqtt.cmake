# monitor/serve --mqtt: the events and the run's state on a real broker (Debian's mosquitto, started
# by the test on a free loopback port), read by mosquitto_sub; and what the options refuse
set(d ${PROJECT_BINARY_DIR}/cli-pipeline)
if(BUILD_MQTT)
  find_program(MOSQUITTO_BROKER mosquitto PATHS /usr/sbin /sbin)
  find_program(MOSQUITTO_SUB mosquitto_sub)
  if(MOSQUITTO_BROKER AND MOSQUITTO_SUB AND BUILD_DASHBOARD)
    add_test(NAME cli.mqtt_broker
             COMMAND sh ${PROJECT_SOURCE_DIR}/tests/cli/mqtt.sh $<TARGET_FILE:twinwatch> ${d}/twin.json ${d}/collision.csv ${d}/mqtt)
    set_tests_properties(cli.mqtt_broker PROPERTIES FIXTURES_REQUIRED "twin;collision_recording" PASS_REGULAR_EXPRESSION "PASS"
                         ENVIRONMENT "PATH=/usr/sbin:/sbin:$ENV{PATH}" TIMEOUT 180)
  else()
    message(WARNING "mosquitto or mosquitto_sub not found: cli.mqtt_broker is not run (scripts/setup.sh installs them)")
  endif()
  add_test(NAME cli.mqtt_bad_topic COMMAND twinwatch monitor --twin ${d}/twin.json ${d}/collision.csv --mqtt localhost --mqtt-topic "plant/+/ur3e")
  set_tests_properties(cli.mqtt_bad_topic PROPERTIES FIXTURES_REQUIRED "twin;collision_recording"
                       PASS_REGULAR_EXPRESSION "--mqtt-topic 'plant/\\+/ur3e': it holds a wildcard")
  add_test(NAME cli.mqtt_bad_port COMMAND twinwatch monitor --twin ${d}/twin.json ${d}/collision.csv --mqtt localhost:70000)
  set_tests_properties(cli.mqtt_bad_port PROPERTIES FIXTURES_REQUIRED "twin;collision_recording"
                       PASS_REGULAR_EXPRESSION "--mqtt 'localhost:70000': the port must be a whole number from 1 to 65535, got '70000'")
  add_test(NAME cli.mqtt_options_need_mqtt COMMAND twinwatch monitor --twin ${d}/twin.json ${d}/collision.csv --mqtt-qos 2)
  set_tests_properties(cli.mqtt_options_need_mqtt PROPERTIES FIXTURES_REQUIRED "twin;collision_recording"
                       PASS_REGULAR_EXPRESSION "--mqtt-qos applies? only with --mqtt")
  add_test(NAME cli.mqtt_password_needs_user COMMAND ${CMAKE_COMMAND} -E env TWINWATCH_MQTT_PASSWORD=secret
           $<TARGET_FILE:twinwatch> monitor --twin ${d}/twin.json ${d}/collision.csv --mqtt localhost --db "")
  set_tests_properties(cli.mqtt_password_needs_user PROPERTIES FIXTURES_REQUIRED "twin;collision_recording"
                       PASS_REGULAR_EXPRESSION "TWINWATCH_MQTT_PASSWORD is set but --mqtt-user is not")
endif()
