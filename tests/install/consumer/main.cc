// Reads a rig log with the installed identification library, checks a message round trip with
// the installed types and visits its fields through the installed list of types, and loads a
// model with the installed core: what a lab's own tool does.
#include <cstdio>
#include <vector>

#include <nimble/rig_message_list.hpp>
#include <nimble/truth_state_t.hpp>

#include "core/model.h"
#include "core/modes.h"
#include "ident/rig_log.h"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: consumer <rig log> <model.yaml>\n");
    return 2;
  }
  nimble::truth_state_t t;
  t.utime = 42;
  t.euler_rad[0] = 0.1;
  std::vector<unsigned char> buf(static_cast<std::size_t>(t.getEncodedSize()));
  t.encode(buf.data(), 0, static_cast<int>(buf.size()));
  nimble::truth_state_t back;
  if (back.decode(buf.data(), 0, static_cast<int>(buf.size())) != static_cast<int>(buf.size()) || back.utime != 42) {
    std::fprintf(stderr, "truth_state_t does not round-trip\n");
    return 1;
  }
  int fields = 0;  // the installed list of types and fields
  nimble::for_each_field(back, [&fields](const char*, const auto&) { ++fields; });
  if (fields != nimble::MessageFields<nimble::truth_state_t>::field_count) {
    std::fprintf(stderr, "the installed message list does not hold truth_state_t's fields\n");
    return 1;
  }
  const nimble::ident::RigLogData log = nimble::ident::read_rig_log(argv[1], nimble::ident::StateSource::kTruth);
  const auto& phi = log.measured.at("phi");
  const nimble::DerivativeModel model = nimble::load_model(argv[2]);
  std::printf("log: %zu phi samples from %s; model: %zu derivatives\n", phi.values.size(), log.state_source.c_str(),
              model.derivatives.size());
  return phi.values.empty() ? 1 : 0;
}
