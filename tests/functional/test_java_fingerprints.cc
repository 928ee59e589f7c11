// Functional test: every Java type in the jar that lcm-spy loads has the fingerprint of
// the C++ type. A mismatch is what makes lcm-spy show a channel as undecodable.

#include <sys/wait.h>

#include <cstdio>
#include <map>
#include <sstream>
#include <string>

#include <catch2/catch.hpp>

#include <nimble/rig_message_list.hpp>

TEST_CASE("Java and C++ fingerprints agree for every type", "[lcmtypes][java]") {
  std::map<std::string, uint64_t> cpp;
  nimble::for_each_message_type([&cpp](auto type) {
    using T = typename decltype(type)::type;
    cpp[std::string("nimble.") + T::getTypeName()] = static_cast<uint64_t>(T::getHash());
  });

  std::string cmd =
      std::string(JAVA_EXE) + " -cp " + FINGERPRINT_CLASSES + ":" + TYPES_JAR + ":" + LCM_JAR + " PrintFingerprints";
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
