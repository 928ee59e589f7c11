/// An error in recorded data (core/data_error.h).

#include "core/data_error.h"

#include <sstream>
#include <utility>

namespace nimble {
namespace {

std::string format_error(const std::string& source, int line, int row, const std::string& column,
                         const std::string& problem) {
  std::ostringstream out;
  out << source;
  if (line > 0) out << ":" << line;
  out << ": ";
  if (row > 0) out << "row " << row << ", ";
  if (!column.empty()) out << "column '" << column << "': ";
  out << problem;
  return out.str();
}

}  // namespace

DataError::DataError(std::string source, int line, int row, std::string column, std::string problem)
    : std::runtime_error(format_error(source, line, row, column, problem)),
      source_(std::move(source)),
      line_(line),
      row_(row),
      column_(std::move(column)),
      problem_(std::move(problem)) {}

}  // namespace nimble
