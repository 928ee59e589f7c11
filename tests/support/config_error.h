#pragma once
/// Test support: requiring that loading inline YAML fails with a ConfigError that names
/// the key (and the value, if given), for loaders read from "inline.yaml".

#include <string>

#include <catch2/catch.hpp>

#include "core/config.h"

namespace nimble::test {

/// Calls `load(text)` and requires a ConfigError for `key` in "inline.yaml".
template <typename Load>
void expect_inline_key_error(Load load, const std::string& text, const std::string& key,
                             const std::string& value = "") {
  INFO("yaml:\n" << text);
  try {
    load(text);
    FAIL("expected a ConfigError for " << key);
  } catch (const ConfigError& e) {
    INFO("message: " << e.what());
    CHECK(e.key() == key);
    CHECK(e.file() == "inline.yaml");
    if (!value.empty()) CHECK(e.value() == value);
    CHECK(std::string(e.what()).find(key) != std::string::npos);
  }
}

}  // namespace nimble::test
