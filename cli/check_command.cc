/// `rig check`: can this host run the rig's LCM multicast, directly or in a private network namespace?

#include <string>
#include <vector>

#include "cmdline/args.h"
#include "cli/commands.h"
#include "launcher/launcher.h"

namespace nimble::cli {

int run_check_command(const std::vector<std::string>& args) {
  std::string json;
  cmdline::CommandLine cl("rig check",
                          "Can this host run the rig's LCM multicast, directly or in a private network namespace?\n"
                          "Prints what works and the commands that fix what does not.");
  cl->footer("Exit code: 0 if a run can start, 1 if not, 2 bad usage.");
  cl.add_json(json, "the findings");
  if (const auto done = cl.parse(args)) return *done;
  return launcher::check_host(json);
}

}  // namespace nimble::cli
