/// `rig params [SECTION]`: the parameters of the sections that declare them in a parameter table
/// (core/param_table.h), with default, allowed range, unit and meaning: the same table the
/// loader and the validation use.

#include <iostream>
#include <string>
#include <vector>

#include "cmdline/args.h"
#include "cli/commands.h"
#include "launcher/run_plan.h"
#include "plant/effects/registry.h"
#include "plant/plant_model.h"
#include "scenario/scenario.h"
#include "can_bridge/bridge_config.h"
#include "controller/attitude_controller.h"
#include "controller/pilot.h"
#include "estimator/ekf.h"
#include "sensors/sensor_config.h"

namespace nimble::cli {
namespace {

constexpr const char* kHeader = "| key | default | allowed | unit | meaning |\n|---|---|---|---|---|\n";

struct Section {
  const char* name;
  std::string (*markdown)();
};

const std::vector<Section>& sections() {
  static const std::vector<Section> list = {
      {"run", [] {
         return params_markdown(launcher::launch_params(), launcher::LaunchConfig{}, "run.") +
                params_markdown(process_run_params(), ProcessRunOptions{}, "run.").substr(std::string(kHeader).size());
       }},
      {"controller", [] {
         return params_markdown(controller_params(), ControllerConfig{}, "controller.") +
                params_markdown(reference_params(), ReferenceGeneratorConfig{}, "controller.reference.{roll,pitch}.")
                    .substr(std::string(kHeader).size()) +
                params_markdown(gain_params(), GainSet{}, "controller.{roll_gain_sets.NAME,pitch_gains,yaw}.")
                    .substr(std::string(kHeader).size());
       }},
      {"plant", [] {
         const auto rows = [](const std::string& md) { return md.substr(std::string(kHeader).size()); };
         return params_markdown(plant::plant_params(), plant::PlantConfig{}, "plant.") +
                rows(params_markdown(plant::flap_actuator_params(), plant::FlapActuatorConfig{}, "plant.flap_actuator.")) +
                rows(params_markdown(plant::servo_params(), plant::ServoConfig{}, "plant.servo.")) +
                rows(params_markdown(plant::thrust_params(), ThrustCurve{}, "plant.thrust.")) +
                rows(params_markdown(plant::initial_params(), plant::InitialState{}, "plant.initial."));
       }},
      {"plant.effects", [] { return plant::effects_markdown(); }},
      {"pilot", [] { return params_markdown(pilot_params(), PilotConfig{}, "pilot."); }},
      {"can_bridge", [] { return params_markdown(can::can_bridge_params(), can::CanBridgeConfig{}, "can_bridge."); }},
      {"lockstep", [] { return params_markdown(lockstep_params(), LockstepOptions{}, "lockstep."); }},
      {"summary", [] { return params_markdown(launcher::judge_params(), launcher::JudgeConfig{}, "summary."); }},
      {"sensing.imu", [] { return params_markdown(imu_params(), ImuModelConfig{}, "sensing.imu."); }},
      {"sensing.mocap", [] { return params_markdown(mocap_params(), MocapConfig{}, "sensing.mocap."); }},
      {"sensing.ekf", [] { return params_markdown(ekf_params(), EkfConfig{}, "sensing.ekf."); }},
  };
  return list;
}

}  // namespace

int run_params_command(const std::vector<std::string>& args) {
  std::string section;
  std::vector<std::string> names;
  for (const auto& s : sections()) names.push_back(s.name);
  CommandLine cl("rig params",
                 "The parameters of a scenario section (default: every section that has a table): key,\n"
                 "default, allowed range, unit and meaning, as Markdown. The same table the loader and\n"
                 "the validation use.");
  cl->add_option("section", section, "one section")->check(CLI::IsMember(names));
  if (const auto done = cl.parse(args)) return *done;
  for (const auto& s : sections()) {
    if (section.empty() || section == s.name) std::cout << "### " << s.name << "\n\n" << s.markdown() << "\n";
  }
  return 0;
}

}  // namespace nimble::cli
