#include "cli/report_files.h"

#include <cstdio>

namespace nimble::cli {

std::string fmt(const char* format, double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, x);
  return buf;
}

}  // namespace nimble::cli
