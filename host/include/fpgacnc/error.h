// Common exception base: an error located in a source file (G-code, step file, config file).
#pragma once

#include <stdexcept>
#include <string>

namespace fpgacnc {

// what() reads "FILE:LINE:COL: error: MESSAGE" (line and column are 1-based; 0 = unknown and
// omitted).
class SourceError : public std::runtime_error {
 public:
  SourceError(std::string file, int line, int column, std::string message);
  const std::string& file() const { return file_; }
  int line() const { return line_; }
  int column() const { return column_; }
  const std::string& message() const { return message_; }

 private:
  std::string file_;
  int line_;
  int column_;
  std::string message_;
};

}  // namespace fpgacnc
