// Functional test: every Java type in the jar that lcm-spy loads has the fingerprint of
// the C++ type. A mismatch is what makes lcm-spy show a channel as undecodable.

#include <sys/wait.h>

#include <cstdio>
#include <map>
#include <sstream>
#include <string>

#include <catch2/catch.hpp>

#include <nimble/actuator_command_t.hpp>
#include <nimble/actuator_feedback_t.hpp>
#include <nimble/attitude_setpoint_t.hpp>
#include <nimble/can_health_t.hpp>
#include <nimble/controller_status_t.hpp>
#include <nimble/estimator_state_t.hpp>
#include <nimble/fault_event_t.hpp>
#include <nimble/heartbeat_t.hpp>
#include <nimble/imu_sample_t.hpp>
#include <nimble/mocap_pose_t.hpp>
#include <nimble/rig_clock_t.hpp>
#include <nimble/run_control_t.hpp>
#include <nimble/step_ack_t.hpp>
#include <nimble/timing_health_t.hpp>
#include <nimble/truth_state_t.hpp>

namespace {

template <typename T>
void add(std::map<std::string, uint64_t>& m) {
  m[std::string("nimble.") + T::getTypeName()] = static_cast<uint64_t>(T::getHash());
}

}  // namespace

TEST_CASE("Java and C++ fingerprints agree for every type", "[lcmtypes][java]") {
  std::map<std::string, uint64_t> cpp;
  add<nimble::actuator_command_t>(cpp);
  add<nimble::actuator_feedback_t>(cpp);
  add<nimble::attitude_setpoint_t>(cpp);
  add<nimble::can_health_t>(cpp);
  add<nimble::controller_status_t>(cpp);
  add<nimble::estimator_state_t>(cpp);
  add<nimble::fault_event_t>(cpp);
  add<nimble::heartbeat_t>(cpp);
  add<nimble::imu_sample_t>(cpp);
  add<nimble::mocap_pose_t>(cpp);
  add<nimble::rig_clock_t>(cpp);
  add<nimble::run_control_t>(cpp);
  add<nimble::step_ack_t>(cpp);
  add<nimble::timing_health_t>(cpp);
  add<nimble::truth_state_t>(cpp);

  std::string cmd = std::string(JAVA_EXE) + " -cp " + FINGERPRINT_CLASSES + ":" + TYPES_JAR + ":" + LCM_JAR +
                    " PrintFingerprints";
  for (const auto& [name, hash] : cpp) cmd += " " + name;
  cmd += " 2>&1";
  FILE* pipe = ::popen(cmd.c_str(), "r");
  REQUIRE(pipe != nullptr);
  std::string output;
  char buf[512];
  while (std::fgets(buf, sizeof buf, pipe)) output += buf;
  const int status = ::pclose(pipe);
  INFO(cmd << "\n" << output);
  REQUIRE(WIFEXITED(status));
  REQUIRE(WEXITSTATUS(status) == 0);

  std::map<std::string, uint64_t> java;
  std::istringstream lines(output);
  std::string name;
  unsigned long long fp = 0;
  while (lines >> name >> fp) java[name] = fp;
  REQUIRE(java.size() == cpp.size());
  for (const auto& [type, hash] : cpp) {
    INFO(type);
    REQUIRE(java.count(type) == 1);
    CHECK(java.at(type) == hash);
  }
}
