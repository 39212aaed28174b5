// rs274ngc expressions for the reader (reader.cpp): '[...]' with LinuxCNC's binary operators and
// precedence, functions, '#' parameters. Reads a line buffer without blanks outside comments,
// letters in upper case (the reader's compacted line), each character with its source column.
#pragma once

#include <string>
#include <string_view>

#include "fpgacnc/gcode/reader.h"

namespace fpgacnc::gcode::detail {

// A value within this of an integer counts as one (G/M codes, parameter numbers).
constexpr double kIntegerTolerance = 1e-6;
// EQ and NE compare with this absolute tolerance (LinuxCNC's TOLERANCE_EQUAL in its documents).
constexpr double kEqualTolerance = 1e-6;

struct Cursor {
  const char* p = nullptr;
  int n = 0;
  const int* cols = nullptr;  // source column of each character; nullptr: column = index + 1
  int end_col = 1;            // column reported at the end of the buffer
  const std::string* file = nullptr;
  int line = 0;

  int col(int i) const {
    if (i >= n) return end_col;
    return cols ? cols[i] : i + 1;
  }
  [[noreturn]] void fail(int column, const std::string& message) const;
};

class Expr {
 public:
  Expr(const Cursor& c, const Params& params) : c_(c), params_(params) {}

  // A real value at i: a number, '#' parameter, '[...]' expression, function or a signed one of
  // these. i moves past it.
  double real_value(int& i);
  // '[...]' at i.
  double bracket(int& i);
  // True when a function call (letters followed by '[') starts at i.
  bool function_at(int i) const;
  // After '#' (i at the first character of the number): the parameter number, checked.
  int param_index(int& i, int hash_col);
  // '<name>' at i: the name lower case, without blanks.
  void named_param(int& i, std::string& name);

 private:
  enum class Op {
    kNone,
    kPow,
    kMul,
    kDiv,
    kMod,
    kAdd,
    kSub,
    kEq,
    kNe,
    kGt,
    kGe,
    kLt,
    kLe,
    kAnd,
    kOr,
    kXor
  };
  double binary(int& i, int min_prec);
  Op peek_op(int i, int& len) const;
  double apply(Op op, double a, double b, int op_col) const;
  double param_value(int& i);
  double function(int& i);

  const Cursor& c_;
  const Params& params_;
};

}  // namespace fpgacnc::gcode::detail
