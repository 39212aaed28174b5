// Helpers shared by the G-code tests: the commands of one kind in a program, and the check that
// a program is refused at file:line:column with a message.
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "fpgacnc/gcode/interpreter.h"

namespace fpgacnc::gcode::test {

// The commands of kind T in a program, in order.
template <typename T>
std::vector<T> all(const Program& p) {
  std::vector<T> r;
  for (const auto& c : p.commands)
    if (const auto* x = std::get_if<T>(&c)) r.push_back(*x);
  return r;
}

inline std::vector<Move> moves_of(const Program& p) {
  return all<Move>(p);
}

// Expects parse_string(text, file, options) to throw at line:col, the message starting with
// "file:line:col: error: " and containing `msg`.
inline void expect_error(std::string_view text, int line, int col, std::string_view msg,
                         const Options& options = {}, const std::string& file = "t.ngc") {
  SCOPED_TRACE(std::string(text));
  try {
    parse_string(text, file, options);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.file(), file);
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_EQ(e.column(), col) << e.what();
    EXPECT_NE(std::string(e.what()).find(msg), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind(
                  file + ":" + std::to_string(line) + ":" + std::to_string(col) + ": error: ", 0),
              0u)
        << e.what();
  }
}

}  // namespace fpgacnc::gcode::test
