#pragma once
/// An error in recorded data (a flight CSV, an LCM log): names the source, the file line, the
/// 1-based data row and the column where it applies (line/row -1 and column empty if not).

#include <stdexcept>
#include <string>

namespace nimble {

/// The error (see above); what() is "source[:line]: [row N, ][column 'C': ]problem".
class DataError : public std::runtime_error {
 public:
  DataError(std::string source, int line, int row, std::string column, std::string problem);

  /// File or log the error is in.
  const std::string& source() const { return source_; }
  /// 1-based line in the file, or -1.
  int line() const { return line_; }
  /// 1-based data row (the first row after the header is row 1), or -1.
  int row() const { return row_; }
  /// Column name, or empty.
  const std::string& column() const { return column_; }
  /// What is wrong, without the location.
  const std::string& problem() const { return problem_; }

 private:
  std::string source_;
  int line_;
  int row_;
  std::string column_;
  std::string problem_;
};

}  // namespace nimble
