#include "expr.h"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <numbers>

namespace fpgacnc::gcode::detail {
namespace {

bool is_digit(char c) {
  return c >= '0' && c <= '9';
}
bool is_alpha(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z');
}
char to_lower(char c) {
  return (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c;
}
constexpr double kDeg = std::numbers::pi / 180.0;

int precedence(int op) {
  // Op order: kNone, kPow, kMul, kDiv, kMod, kAdd, kSub, kEq..kLe, kAnd, kOr, kXor
  if (op == 1) return 4;
  if (op <= 4) return 3;
  if (op <= 6) return 2;
  if (op <= 12) return 1;
  return 0;
}

}  // namespace

void Cursor::fail(int column, const std::string& message) const {
  throw Error(*file, line, column, message);
}

double Expr::real_value(int& i) {
  if (i >= c_.n) c_.fail(c_.col(i), "expected a value at the end of the line");
  const char ch = c_.p[i];
  if (ch == '[') return bracket(i);
  if (ch == '#') return param_value(i);
  if (ch == '+' || ch == '-') {
    ++i;
    const double v = real_value(i);
    return ch == '-' ? 0.0 - v : v;  // 0 - v: no "-0" (LinuxCNC prints -[0] as 0)
  }
  if (is_digit(ch) || ch == '.') {
    const int start = i;
    bool dot = false;
    int digits = 0;
    while (i < c_.n && (is_digit(c_.p[i]) || (c_.p[i] == '.' && !dot))) {
      if (c_.p[i] == '.') {
        dot = true;
      } else {
        ++digits;
      }
      ++i;
    }
    if (digits == 0) c_.fail(c_.col(start), "expected a number, found '.'");
    double v = 0.0;
    const auto r = std::from_chars(c_.p + start, c_.p + i, v);
    if (r.ec != std::errc() || r.ptr != c_.p + i || !std::isfinite(v))
      c_.fail(c_.col(start), "invalid number");
    return v;
  }
  if (is_alpha(ch)) return function(i);
  if (ch == ']') c_.fail(c_.col(i), "expected a value before ']'");
  c_.fail(c_.col(i), fmt::format("expected a value, found '{}'", ch));
}

double Expr::bracket(int& i) {
  const int open = i;
  ++i;
  const double v = binary(i, 0);
  if (i >= c_.n) c_.fail(c_.col(open), "unclosed '[' (no matching ']')");
  if (c_.p[i] != ']')
    c_.fail(c_.col(i), fmt::format("expected an operator or ']', found '{}'", c_.p[i]));
  ++i;
  return v;
}

double Expr::binary(int& i, int min_prec) {
  double lhs = real_value(i);
  for (;;) {
    int len = 0;
    const Op op = peek_op(i, len);
    if (op == Op::kNone) return lhs;
    const int prec = precedence(static_cast<int>(op));
    if (prec < min_prec) return lhs;
    const int op_col = c_.col(i);
    i += len;
    const double rhs = binary(i, prec + 1);
    lhs = apply(op, lhs, rhs, op_col);
  }
}

Expr::Op Expr::peek_op(int i, int& len) const {
  if (i >= c_.n) return Op::kNone;
  const char* s = c_.p + i;
  const int left = c_.n - i;
  len = 1;
  switch (s[0]) {
    case '*':
      if (left >= 2 && s[1] == '*') {
        len = 2;
        return Op::kPow;
      }
      return Op::kMul;
    case '/':
      return Op::kDiv;
    case '+':
      return Op::kAdd;
    case '-':
      return Op::kSub;
    case ']':
      return Op::kNone;
    default:
      break;
  }
  if (!is_alpha(s[0]))
    c_.fail(c_.col(i), fmt::format("expected an operator or ']', found '{}'", s[0]));
  auto is = [&](const char* w, int l) {
    if (left < l) return false;
    for (int k = 0; k < l; ++k)
      if (s[k] != w[k]) return false;
    len = l;
    return true;
  };
  if (is("MOD", 3)) return Op::kMod;
  if (is("AND", 3)) return Op::kAnd;
  if (is("XOR", 3)) return Op::kXor;
  if (is("OR", 2)) return Op::kOr;
  if (is("EQ", 2)) return Op::kEq;
  if (is("NE", 2)) return Op::kNe;
  if (is("GT", 2)) return Op::kGt;
  if (is("GE", 2)) return Op::kGe;
  if (is("LT", 2)) return Op::kLt;
  if (is("LE", 2)) return Op::kLe;
  int k = i;
  while (k < c_.n && is_alpha(c_.p[k])) ++k;
  c_.fail(c_.col(i),
          fmt::format("unknown operator '{}'", std::string_view(s, static_cast<size_t>(k - i))));
}

double Expr::apply(Op op, double a, double b, int op_col) const {
  double r = 0.0;
  switch (op) {
    case Op::kPow:
      if (a < 0 && b != std::round(b))
        c_.fail(op_col, "negative number raised to a non-integer power");
      r = std::pow(a, b);
      break;
    case Op::kMul:
      r = a * b;
      break;
    case Op::kDiv:
      if (b == 0.0) c_.fail(op_col, "division by zero");
      r = a / b;
      break;
    case Op::kMod:
      if (b == 0.0) c_.fail(op_col, "MOD by zero");
      r = std::fmod(a, b);
      if (r < 0) r += std::fabs(b);
      break;
    case Op::kAdd:
      r = a + b;
      break;
    case Op::kSub:
      r = a - b;
      break;
    case Op::kEq:
      r = std::fabs(a - b) < kEqualTolerance ? 1.0 : 0.0;
      break;
    case Op::kNe:
      r = std::fabs(a - b) < kEqualTolerance ? 0.0 : 1.0;
      break;
    case Op::kGt:
      r = a > b ? 1.0 : 0.0;
      break;
    case Op::kGe:
      r = a >= b ? 1.0 : 0.0;
      break;
    case Op::kLt:
      r = a < b ? 1.0 : 0.0;
      break;
    case Op::kLe:
      r = a <= b ? 1.0 : 0.0;
      break;
    case Op::kAnd:
      r = (a != 0.0 && b != 0.0) ? 1.0 : 0.0;
      break;
    case Op::kOr:
      r = (a != 0.0 || b != 0.0) ? 1.0 : 0.0;
      break;
    case Op::kXor:
      r = ((a != 0.0) != (b != 0.0)) ? 1.0 : 0.0;
      break;
    case Op::kNone:
      break;
  }
  if (!std::isfinite(r)) c_.fail(op_col, "the result is not a finite number");
  return r == 0.0 ? 0.0 : r;  // -0 (from fmod or a product) reads as 0
}

void Expr::named_param(int& i, std::string& name) {
  const int open = i;
  ++i;
  name.clear();
  while (i < c_.n && c_.p[i] != '>') name += to_lower(c_.p[i++]);
  if (i >= c_.n) c_.fail(c_.col(open), "unterminated parameter name '<' (no '>')");
  if (name.empty()) c_.fail(c_.col(open), "empty parameter name '<>'");
  ++i;
}

int Expr::param_index(int& i, int hash_col) {
  const double v = real_value(i);
  const double r = std::round(v);
  if (std::fabs(v - r) > kIntegerTolerance)
    c_.fail(hash_col, fmt::format("parameter number {} is not an integer", v));
  if (r < 1 || r >= Params::kCount)
    c_.fail(hash_col,
            fmt::format("parameter number {} is out of range (1..{})", r, Params::kCount - 1));
  return static_cast<int>(r);
}

double Expr::param_value(int& i) {
  const int hash_col = c_.col(i);
  ++i;
  if (i < c_.n && c_.p[i] == '<') {
    std::string name;
    named_param(i, name);
    const auto v = params_.named(name);
    if (!v) c_.fail(hash_col, fmt::format("parameter #<{}> is not set", name));
    return *v;
  }
  return params_.get(param_index(i, hash_col));
}

bool Expr::function_at(int i) const {
  int k = i;
  while (k < c_.n && is_alpha(c_.p[k])) ++k;
  return k > i && k < c_.n && c_.p[k] == '[';
}

double Expr::function(int& i) {
  const int fcol = c_.col(i);
  const int start = i;
  while (i < c_.n && is_alpha(c_.p[i])) ++i;
  const std::string_view name(c_.p + start, static_cast<size_t>(i - start));
  if (i >= c_.n || c_.p[i] != '[') {
    c_.fail(fcol, fmt::format("unexpected '{}' in an expression (a function needs its argument in "
                              "brackets, e.g. SIN[30])",
                              name));
  }
  if (name == "EXISTS") {
    ++i;
    if (i + 1 >= c_.n || c_.p[i] != '#' || c_.p[i + 1] != '<')
      c_.fail(fcol, "EXISTS takes one named parameter: EXISTS[#<name>]");
    ++i;
    std::string pname;
    named_param(i, pname);
    if (i >= c_.n || c_.p[i] != ']')
      c_.fail(fcol, "EXISTS takes one named parameter: EXISTS[#<name>]");
    ++i;
    return params_.named(pname) ? 1.0 : 0.0;
  }
  if (name == "ATAN") {
    const double y = bracket(i);
    if (i + 1 >= c_.n || c_.p[i] != '/' || c_.p[i + 1] != '[')
      c_.fail(fcol, "ATAN needs two arguments: ATAN[y]/[x]");
    ++i;
    const double x = bracket(i);
    return std::atan2(y, x) / kDeg;
  }
  enum F { kAbs, kAcos, kAsin, kCos, kExp, kFix, kFup, kRound, kLn, kSin, kSqrt, kTan };
  static constexpr std::pair<std::string_view, F> kNames[] = {
      {"ABS", kAbs}, {"ACOS", kAcos}, {"ASIN", kAsin}, {"COS", kCos},
      {"EXP", kExp}, {"FIX", kFix},   {"FUP", kFup},   {"ROUND", kRound},
      {"LN", kLn},   {"SIN", kSin},   {"SQRT", kSqrt}, {"TAN", kTan}};
  const F* f = nullptr;
  for (const auto& [nm, id] : kNames)
    if (nm == name) f = &id;
  if (!f) c_.fail(fcol, fmt::format("unknown function '{}'", name));
  const double a = bracket(i);
  double r = 0.0;
  switch (*f) {
    case kAbs:
      r = std::fabs(a);
      break;
    case kAcos:
      if (a < -1.0 || a > 1.0) c_.fail(fcol, fmt::format("ACOS argument {} is outside [-1, 1]", a));
      r = std::acos(a) / kDeg;
      break;
    case kAsin:
      if (a < -1.0 || a > 1.0) c_.fail(fcol, fmt::format("ASIN argument {} is outside [-1, 1]", a));
      r = std::asin(a) / kDeg;
      break;
    case kCos:
      r = std::cos(a * kDeg);
      break;
    case kExp:
      r = std::exp(a);
      break;
    case kFix:
      r = std::floor(a);
      break;
    case kFup:
      r = std::ceil(a);
      break;
    case kRound:
      r = std::round(a);
      break;
    case kLn:
      if (a <= 0.0) c_.fail(fcol, fmt::format("LN of {} (needs a positive number)", a));
      r = std::log(a);
      break;
    case kSin:
      r = std::sin(a * kDeg);
      break;
    case kSqrt:
      if (a < 0.0) c_.fail(fcol, fmt::format("SQRT of a negative number ({})", a));
      r = std::sqrt(a);
      break;
    case kTan:
      r = std::tan(a * kDeg);
      break;
  }
  if (!std::isfinite(r)) c_.fail(fcol, fmt::format("{} result is not a finite number", name));
  return r;
}

}  // namespace fpgacnc::gcode::detail
