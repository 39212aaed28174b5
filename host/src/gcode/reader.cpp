// The reader: program text -> Blocks (see reader.h). One pass per line: lexing, checksums and,
// in rs274ngc files, parameters, expressions (expr.h) and O-word control flow.
#include "fpgacnc/gcode/reader.h"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <unordered_map>

#include "expr.h"

namespace fpgacnc::gcode {

// ---------------------------------------------------------------------------------------------
// Params

Params::Params() : numbered_(kCount, 0.0), locals_(1) {
  globals_["_value"] = 0.0;
  globals_["_value_returned"] = 0.0;
}

double Params::get(int n) const {
  return numbered_[static_cast<size_t>(n)];
}

void Params::set(int n, double value) {
  numbered_[static_cast<size_t>(n)] = value;
}

std::optional<double> Params::named(std::string_view name) const {
  const auto& m = (!name.empty() && name[0] == '_') ? globals_ : locals_.back();
  const auto it = m.find(name);
  if (it == m.end()) return std::nullopt;
  return it->second;
}

void Params::set_named(std::string_view name, double value) {
  auto& m = (!name.empty() && name[0] == '_') ? globals_ : locals_.back();
  const auto it = m.find(name);
  if (it != m.end()) {
    it->second = value;
  } else {
    m.emplace(std::string(name), value);
  }
}

void Params::push_frame() {
  saved_args_.emplace_back(numbered_.begin() + 1, numbered_.begin() + 31);
  std::fill(numbered_.begin() + 1, numbered_.begin() + 31, 0.0);
  locals_.emplace_back();
}

void Params::pop_frame() {
  if (saved_args_.empty()) return;
  std::copy(saved_args_.back().begin(), saved_args_.back().end(), numbered_.begin() + 1);
  saved_args_.pop_back();
  locals_.pop_back();
}

// ---------------------------------------------------------------------------------------------
// Reader

namespace {

constexpr int kMaxCallFrames = 10;  // LinuxCNC: 10 levels, the main program included
constexpr int kMaxArgs = 30;

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r';
}
bool is_digit(char c) {
  return c >= '0' && c <= '9';
}
bool is_alpha(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z');
}
char to_upper(char c) {
  return (c >= 'a' && c <= 'z') ? static_cast<char>(c - 'a' + 'A') : c;
}
char to_lower(char c) {
  return (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c;
}
bool non_printable(unsigned char c) {
  return (c < 0x20 && c != '\t' && c != '\r') || c == 0x7F;
}

enum class Kw : uint8_t {
  kNone,  // 'O100' alone: a (Fanuc-style) program number, ignored
  kSub,
  kEndsub,
  kReturn,
  kCall,
  kDo,
  kWhile,
  kEndwhile,
  kIf,
  kElseif,
  kElse,
  kEndif,
  kBreak,
  kContinue,
  kRepeat,
  kEndrepeat,
  kUnknown,
};

// The O-word keyword at the start of `w` (upper case, blanks removed): the longest one that is a
// prefix ("SUBG0" is 'sub' followed by G0, as LinuxCNC reads a line without its blanks). `len`
// gets its length.
Kw keyword(std::string_view w, size_t& len) {
  static constexpr std::pair<std::string_view, Kw> kTable[] = {
      {"ENDREPEAT", Kw::kEndrepeat},
      {"ENDWHILE", Kw::kEndwhile},
      {"CONTINUE", Kw::kContinue},
      {"ENDSUB", Kw::kEndsub},
      {"RETURN", Kw::kReturn},
      {"ELSEIF", Kw::kElseif},
      {"REPEAT", Kw::kRepeat},
      {"WHILE", Kw::kWhile},
      {"ENDIF", Kw::kEndif},
      {"BREAK", Kw::kBreak},
      {"CALL", Kw::kCall},
      {"ELSE", Kw::kElse},
      {"SUB", Kw::kSub},
      {"DO", Kw::kDo},
      {"IF", Kw::kIf},
  };
  len = 0;
  if (w.empty()) return Kw::kNone;
  for (const auto& [name, kw] : kTable) {
    if (w.substr(0, name.size()) == name) {
      len = name.size();
      return kw;
    }
  }
  return Kw::kUnknown;
}

const char* kw_name(Kw k) {
  switch (k) {
    case Kw::kSub:
      return "sub";
    case Kw::kEndsub:
      return "endsub";
    case Kw::kReturn:
      return "return";
    case Kw::kCall:
      return "call";
    case Kw::kDo:
      return "do";
    case Kw::kWhile:
      return "while";
    case Kw::kEndwhile:
      return "endwhile";
    case Kw::kIf:
      return "if";
    case Kw::kElseif:
      return "elseif";
    case Kw::kElse:
      return "else";
    case Kw::kEndif:
      return "endif";
    case Kw::kBreak:
      return "break";
    case Kw::kContinue:
      return "continue";
    case Kw::kRepeat:
      return "repeat";
    case Kw::kEndrepeat:
      return "endrepeat";
    default:
      return "";
  }
}

// One O-word line of the file, found before running (labels are matched by name, as LinuxCNC
// does: the lines between are skipped without being read).
struct OEntry {
  int line = 0;  // 0-based
  Kw kw = Kw::kNone;
  bool do_tail = false;  // a 'while' that closes a 'do'
};

bool is_text_mcode(int code) {
  return code == 117 || code == 118 || code == 23 || code == 28 || code == 30 || code == 32 ||
         code == 928;
}

std::string dialect_suffix(const Syntax& s) {
  if (s.dialect_name && *s.dialect_name)
    return fmt::format("; this file's dialect is {}", s.dialect_name);
  return ", not enabled for this file's dialect";
}

}  // namespace

struct Reader::Impl {
  Impl(std::string f, std::string t, Syntax s, Params& p)
      : file(std::move(f)), text(std::move(t)), syn(s), params(p) {
    if (syn.ngc) index_lines();
    frames.emplace_back();
    frames.back().label = "main";
  }

  std::string file;
  std::string text;
  Syntax syn;
  Params& params;
  bool ended = false;
  bool block_delete_on = false;
  uint64_t loop_limit = kDefaultLoopLimit;

  // Lines. Without rs274ngc the text is read front to back (pos); with it, by line index (cur)
  // so that loops and calls can jump.
  size_t pos = 0;
  int seq_line = 0;
  std::vector<size_t> starts;  // starts[i]: offset of line i; starts[nlines]: end sentinel
  int nlines = 0;
  int cur = 0;
  std::unordered_map<std::string, std::vector<OEntry>> oindex;

  struct Frame {
    std::string label;                             // "o100" / "o<name>"; "main" for the program
    int call_line = 0;                             // 1-based line of the call
    int return_line = 0;                           // 0-based index of the line after the call
    std::vector<std::pair<int, int64_t>> repeats;  // repeat line -> iterations left
    std::vector<std::pair<int, uint64_t>> loops;   // loop head line -> jumps back so far
  };
  std::vector<Frame> frames;
  int jumped_to = -1;  // the while line an endwhile jumped back to

  // The line being lexed: its original text, and the buffer the lexer reads (the original text,
  // or for rs274ngc the line without blanks outside comments, upper case, with each character's
  // original column in cols).
  std::string_view orig;
  int lnum = 0;
  std::string buf;
  std::vector<int> cols;
  const char* p = nullptr;
  int n = 0;
  bool compacted = false;

  struct Pending {
    int index = 0;  // numbered parameter, or 0 for a named one
    std::string name;
    double value = 0.0;
  };
  std::vector<Pending> pending;
  size_t npending = 0;

  int col(int i) const {
    if (!compacted) return i + 1;
    if (i < n) return cols[static_cast<size_t>(i)];
    return static_cast<int>(orig.size()) + 1;
  }

  [[noreturn]] void fail(int c, const std::string& msg) const { throw Error(file, lnum, c, msg); }
  [[noreturn]] void fail_at(int line0, int c, const std::string& msg) const {
    throw Error(file, line0 + 1, c, msg);
  }

  // ---- lines ---------------------------------------------------------------------------------

  std::string_view line_text(int i) const {
    const size_t a = starts[static_cast<size_t>(i)];
    const size_t b = starts[static_cast<size_t>(i) + 1] - 1;  // without its '\n'
    return std::string_view(text).substr(a, b - a);
  }

  void index_lines() {
    size_t a = 0;
    while (a < text.size()) {
      starts.push_back(a);
      const void* nl = std::memchr(text.data() + a, '\n', text.size() - a);
      a = nl ? static_cast<size_t>(static_cast<const char*>(nl) - text.data()) + 1 : text.size();
    }
    nlines = static_cast<int>(starts.size());
    // End sentinel: one past the last line's (possibly missing) '\n'.
    starts.push_back(!text.empty() && text.back() == '\n' ? text.size() : text.size() + 1);
    for (int i = 0; i < nlines; ++i) index_o_line(i);
    // A 'while' closes a 'do' when the nearest earlier loop line of its label is that 'do'.
    for (auto& [label, entries] : oindex) {
      Kw last = Kw::kNone;
      for (auto& e : entries) {
        if (e.kw == Kw::kWhile) e.do_tail = last == Kw::kDo;
        if (e.kw == Kw::kDo || e.kw == Kw::kWhile || e.kw == Kw::kEndwhile) last = e.kw;
        if (e.kw == Kw::kWhile && e.do_tail) last = Kw::kNone;
      }
    }
  }

  // Finds the label and keyword of an O-word line without evaluating anything (never throws:
  // a malformed line is reported when it runs).
  void index_o_line(int i) {
    const std::string_view s = line_text(i);
    size_t k = 0;
    auto skip = [&] {
      while (k < s.size() && is_space(s[k])) ++k;
    };
    skip();
    if (k < s.size() && s[k] == '/') ++k;
    skip();
    if (k < s.size() && (s[k] == 'N' || s[k] == 'n')) {
      ++k;
      while (k < s.size() && (is_digit(s[k]) || is_space(s[k]) || s[k] == '.')) ++k;
    }
    if (k >= s.size() || (s[k] != 'O' && s[k] != 'o')) return;
    ++k;
    skip();
    std::string label = "o";
    if (k < s.size() && s[k] == '<') {
      label += '<';
      ++k;
      while (k < s.size() && s[k] != '>') {
        if (!is_space(s[k])) label += to_lower(s[k]);
        ++k;
      }
      if (k >= s.size()) return;
      label += '>';
      ++k;
    } else {
      std::string digits;
      while (k < s.size() && (is_digit(s[k]) || is_space(s[k]))) {
        if (is_digit(s[k])) digits += s[k];
        ++k;
      }
      if (digits.empty()) return;  // computed label: only 'call' takes one
      size_t z = 0;
      while (z + 1 < digits.size() && digits[z] == '0') ++z;
      label += digits.substr(z);
    }
    std::string word;
    while (k < s.size() && (is_alpha(s[k]) || is_space(s[k]))) {
      if (!is_space(s[k])) word += to_upper(s[k]);
      ++k;
    }
    size_t len = 0;
    const Kw kw = keyword(word, len);
    if (kw == Kw::kNone || kw == Kw::kUnknown) return;
    oindex[label].push_back(OEntry{i, kw, false});
  }

  const std::vector<OEntry>* entries(const std::string& label) const {
    const auto it = oindex.find(label);
    return it == oindex.end() ? nullptr : &it->second;
  }

  // First O-line of `label` after line `from` whose keyword is in `kws` (loop-closing 'while'
  // lines are told apart from loop heads by do_tail: kw kWhile matches heads only, kDo matches
  // tails).
  const OEntry* find_after(const std::string& label, int from, std::initializer_list<Kw> kws,
                           bool want_do_tail = false) const {
    const auto* es = entries(label);
    if (!es) return nullptr;
    for (const auto& e : *es) {
      if (e.line <= from) continue;
      for (Kw k : kws) {
        if (k == Kw::kWhile && e.kw == Kw::kWhile && e.do_tail != want_do_tail) continue;
        if (e.kw == k) return &e;
      }
    }
    return nullptr;
  }
  const OEntry* find_before(const std::string& label, int from, Kw kw,
                            bool want_do_tail = false) const {
    const auto* es = entries(label);
    if (!es) return nullptr;
    const OEntry* found = nullptr;
    for (const auto& e : *es) {
      if (e.line >= from) break;
      if (e.kw == kw && (kw != Kw::kWhile || e.do_tail == want_do_tail)) found = &e;
    }
    return found;
  }

  bool fetch(int& line0) {
    if (syn.ngc) {
      if (cur >= nlines) return false;
      line0 = cur++;
      orig = line_text(line0);
      lnum = line0 + 1;
      return true;
    }
    if (pos >= text.size()) return false;
    const void* nl = std::memchr(text.data() + pos, '\n', text.size() - pos);
    const size_t end =
        nl ? static_cast<size_t>(static_cast<const char*>(nl) - text.data()) : text.size();
    orig = std::string_view(text).substr(pos, end - pos);
    pos = end + 1;
    line0 = seq_line++;
    lnum = line0 + 1;
    return true;
  }

  // ---- lexing --------------------------------------------------------------------------------

  void compact() {
    buf.clear();
    cols.clear();
    const size_t len = orig.size();
    for (size_t i = 0; i < len; ++i) {
      const auto c = static_cast<unsigned char>(orig[i]);
      if (c == ' ' || c == '\t' || c == '\r') continue;
      if (non_printable(c))
        fail(static_cast<int>(i) + 1, fmt::format("non-printable byte 0x{:02X}", c));
      if (c == '(') {
        const size_t j = static_cast<size_t>(
            scan_comment(orig.data(), static_cast<int>(len), static_cast<int>(i), true));
        for (size_t k = i; k <= j; ++k) {
          buf.push_back(orig[k]);
          cols.push_back(static_cast<int>(k) + 1);
        }
        i = j;
        continue;
      }
      if (c == ';' && syn.semicolon_comments) {
        for (size_t k = i; k < len; ++k) {
          const auto d = static_cast<unsigned char>(orig[k]);
          if (non_printable(d))
            fail(static_cast<int>(k) + 1, fmt::format("non-printable byte 0x{:02X}", d));
          buf.push_back(orig[k]);
          cols.push_back(static_cast<int>(k) + 1);
        }
        break;
      }
      if (c >= 0x80) fail(static_cast<int>(i) + 1, fmt::format("non-ASCII byte 0x{:02X}", c));
      buf.push_back(to_upper(static_cast<char>(c)));
      cols.push_back(static_cast<int>(i) + 1);
    }
    p = buf.data();
    n = static_cast<int>(buf.size());
    compacted = true;
  }

  // '%', '$' and '?' lines (checked on the original text). Returns true when the line is one.
  bool special_line(Block& out) {
    size_t a = 0;
    while (a < orig.size() && is_space(orig[a])) ++a;
    if (a >= orig.size()) return false;
    const char c = orig[a];
    if (syn.macro_lines && is_alpha(c) && a + 1 < orig.size() &&
        (is_alpha(orig[a + 1]) || orig[a + 1] == '_')) {
      size_t b = orig.size();
      while (b > a && is_space(orig[b - 1])) --b;
      out.kind = BlockKind::kMacro;
      out.text.assign(orig.substr(a, b - a));
      out.text_col = static_cast<int>(a) + 1;
      return true;
    }
    if (c != '%' && c != '$' && c != '?') return false;
    size_t b = orig.size();
    while (b > a && is_space(orig[b - 1])) --b;
    for (size_t k = a; k < b; ++k) {
      const auto d = static_cast<unsigned char>(orig[k]);
      if (non_printable(d))
        fail(static_cast<int>(k) + 1, fmt::format("non-printable byte 0x{:02X}", d));
      if (d >= 0x80 && c != '%')
        fail(static_cast<int>(k) + 1, fmt::format("non-ASCII byte 0x{:02X}", d));
    }
    if (c == '%') {
      size_t t = a + 1;
      while (t < b && is_space(orig[t])) ++t;
      out.kind = BlockKind::kPercent;
      out.text.assign(orig.substr(t, b - t));
      out.text_col = static_cast<int>(t) + 1;
      return true;
    }
    if (!syn.dollar_lines) {
      fail(static_cast<int>(a) + 1,
           c == '$' ? "'$' lines are grbl system commands" + dialect_suffix(syn)
                    : "'?' lines are grbl status queries" + dialect_suffix(syn));
    }
    out.kind = c == '$' ? BlockKind::kSystem : BlockKind::kQuery;
    out.text.assign(orig.substr(a, b - a));
    out.text_col = static_cast<int>(a) + 1;
    return true;
  }

  // The ')' closing the comment that opens at s[open]. With Syntax::paren_in_comment a '(' inside
  // opens a nested pair ("(tool (1/8 in))" is one comment) and, if the nesting never closes, the
  // comment ends at the line's last ')'; without it a '(' inside is an error. Checks the bytes.
  int scan_comment(const char* s, int len, int open, bool original) {
    auto at = [&](int k) { return original ? k + 1 : col(k); };
    int depth = 1;
    int last_close = -1;
    for (int j = open + 1; j < len; ++j) {
      const auto d = static_cast<unsigned char>(s[j]);
      if (non_printable(d)) fail(at(j), fmt::format("non-printable byte 0x{:02X}", d));
      if (d == '(') {
        if (!syn.paren_in_comment) fail(at(j), "'(' inside a comment");
        ++depth;
      } else if (d == ')') {
        last_close = j;
        if (--depth == 0) return j;
      }
    }
    if (last_close < 0) fail(at(open), "unterminated comment '('");
    return last_close;
  }
  int comment_end(int i) { return scan_comment(p, n, i, !compacted); }

  void check_rest_printable(int i) {
    if (compacted) return;
    for (int j = i; j < n; ++j) {
      const auto d = static_cast<unsigned char>(p[j]);
      if (non_printable(d)) fail(j + 1, fmt::format("non-printable byte 0x{:02X}", d));
    }
  }

  unsigned xor_before(int i) const {
    const int orig_end = col(i) - 1;
    unsigned x = 0;
    for (int k = 0; k < orig_end; ++k)
      x ^= static_cast<unsigned char>(orig[static_cast<size_t>(k)]);
    return x;
  }

  // '*<n>' at i: verify and return (the rest of the line may only be blank or a ';' comment).
  void checksum(int i) {
    const unsigned x = xor_before(i);
    int j = i + 1;
    unsigned given = 0;
    int digits = 0;
    while (j < n && is_digit(p[j]) && digits < 4) {
      given = given * 10 + static_cast<unsigned>(p[j] - '0');
      ++j;
      ++digits;
    }
    while (j < n && is_space(p[j])) ++j;
    if (digits == 0 || given > 255 || (j < n && !(p[j] == ';' && syn.semicolon_comments))) {
      fail(col(i), "malformed checksum (expected *0..255 at the end of the line)");
    }
    check_rest_printable(j);
    if (given != x) {
      fail(col(i), fmt::format("checksum mismatch: line says {}, computed {}", given, x));
    }
  }

  [[noreturn]] void bad_char(int i) const {
    const auto c = static_cast<unsigned char>(p[i]);
    if (non_printable(c)) fail(col(i), fmt::format("non-printable byte 0x{:02X}", c));
    if (c >= 0x80) fail(col(i), fmt::format("non-ASCII byte 0x{:02X}", c));
    if (c == '#')
      fail(col(i), "'#' parameters are rs274ngc (LinuxCNC) syntax" + dialect_suffix(syn));
    if (c == '[')
      fail(col(i), "'[' expressions are rs274ngc (LinuxCNC) syntax" + dialect_suffix(syn));
    if (c == ']') fail(col(i), syn.ngc ? "unbalanced ']'" : "unexpected character ']'");
    if (c == ';')
      fail(col(i), "unexpected character ';' (';' comments are not enabled for this file)");
    if (c == '*') {
      fail(col(i), syn.ngc ? "unexpected '*' outside an expression '[...]'"
                           : "unexpected character '*' (checksums are not enabled for this file)");
    }
    fail(col(i), fmt::format("unexpected character '{}'", static_cast<char>(c)));
  }

  void push_word(Block& out, const Word& w) {
    if (out.count == Block::kMaxWords) fail(w.col, "too many words on one line");
    out.words[static_cast<size_t>(out.count++)] = w;
  }

  // A plain number at i (sign, digits, one '.'); returns false when there are no digits.
  // On success i is past it.
  bool plain_number(int& i, double& v, bool& dot) {
    int j = i;
    bool neg = false;
    if (j < n && (p[j] == '+' || p[j] == '-')) {
      neg = p[j] == '-';
      ++j;
    }
    const int start = j;
    int ndig = 0;
    int frac = 0;    // digits after the point
    uint64_t m = 0;  // the digits as an integer, while it is exact in a double
    dot = false;
    while (j < n) {
      if (is_digit(p[j])) {
        ++ndig;
        frac += dot;
        m = m < (uint64_t{1} << 49) ? m * 10 + static_cast<uint64_t>(p[j] - '0') : ~uint64_t{0};
      } else if (p[j] == '.' && !dot) {
        dot = true;
      } else {
        break;
      }
      ++j;
    }
    if (ndig == 0) return false;
    // Clinger's fast path: m and 10^frac are exact doubles (m < 2^53, frac <= 22), so one
    // correctly rounded division gives the same double as from_chars, at a fraction of its cost.
    static constexpr double kPow10[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                          1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                          1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
    if (m < (uint64_t{1} << 53) && frac <= 22) {
      v = static_cast<double>(m) / kPow10[frac];
    } else {
      const auto res = std::from_chars(p + start, p + j, v);
      if (res.ec != std::errc() || res.ptr != p + j || !std::isfinite(v)) {
        fail(col(start), "invalid number");
      }
    }
    if (neg) v = -v;
    i = j;
    return true;
  }

  detail::Cursor cursor_;
  detail::Expr expr() {
    cursor_ = detail::Cursor{
        p, n, compacted ? cols.data() : nullptr, static_cast<int>(orig.size()) + 1, &file, lnum};
    return detail::Expr(cursor_, params);
  }

  // Text of a Marlin text M-code: the rest of the original line after index i.
  void text_mcode(Block& out, int i) {
    size_t a = static_cast<size_t>(col(i) - 1);
    if (a > orig.size()) a = orig.size();
    size_t b = orig.size();
    if (syn.semicolon_comments) {
      const size_t semi = orig.find(';', a);
      if (semi != std::string_view::npos) b = semi;
    }
    if (syn.checksums) {
      const size_t star = orig.rfind('*', b == 0 ? 0 : b - 1);
      if (star != std::string_view::npos && star >= a) {
        size_t k = star + 1;
        size_t digits = 0;
        while (k < b && is_digit(orig[k])) ++k, ++digits;
        while (k < b && is_space(orig[k])) ++k;
        if (digits > 0 && k == b) {
          // The checksum of a text line (Marlin): checked like any other.
          const int save_n = n;
          const char* save_p = p;
          const bool save_c = compacted;
          p = orig.data();
          n = static_cast<int>(b);
          compacted = false;
          checksum(static_cast<int>(star));
          p = save_p;
          n = save_n;
          compacted = save_c;
          b = star;
        }
      }
    }
    for (size_t k = a; k < orig.size(); ++k) {
      const auto d = static_cast<unsigned char>(orig[k]);
      if (non_printable(d))
        fail(static_cast<int>(k) + 1, fmt::format("non-printable byte 0x{:02X}", d));
    }
    while (a < b && is_space(orig[a])) ++a;
    while (b > a && is_space(orig[b - 1])) --b;
    out.message_kind = MessageKind::kText;
    out.text.assign(orig.substr(a, b - a));
    out.text_col = static_cast<int>(a) + 1;
  }

  // Lexes the current line into `out`. Returns false for an O-word line (already executed).
  bool lex(Block& out, int line0) {
    out.line = lnum;
    out.kind = BlockKind::kWords;
    out.block_delete = false;
    out.count = 0;
    out.message_kind = MessageKind::kNone;
    out.text.clear();
    out.text_col = 0;
    if (special_line(out)) return true;
    if (syn.ngc) {
      compact();
    } else {
      p = orig.data();
      n = static_cast<int>(orig.size());
      compacted = false;
    }
    npending = 0;
    int last_comment = -1;  // index of the '(' of the line's last comment (rs274ngc)
    int i = 0;
    while (i < n && is_space(p[i])) ++i;
    if (i < n && p[i] == '/') {
      if (block_delete_on) return false;
      out.block_delete = true;
      ++i;
    }
    while (i < n) {
      const char c = p[i];
      if (is_space(c)) {
        ++i;
        continue;
      }
      // A word: a letter, or LinuxCNC's polar '@' (distance) and '^' (angle), and its value.
      if (is_alpha(c) || ((c == kPolarRadius || c == kPolarAngle) && syn.ngc)) {
        const char letter = is_alpha(c) ? to_upper(c) : c;
        const int wcol = col(i);
        if (letter == 'O') {
          if (!syn.ngc) fail(wcol, "O-words are rs274ngc (LinuxCNC) syntax" + dialect_suffix(syn));
          for (int w = 0; w < out.count; ++w) {
            if (out.words[static_cast<size_t>(w)].letter != 'N')
              fail(wcol,
                   "an O-word must be the first word on its line (only N may come before it)");
          }
          if (npending > 0) fail(wcol, "an O-word line cannot have parameter assignments");
          return o_line(out, line0, i + 1, wcol);
        }
        ++i;
        while (i < n && is_space(p[i])) ++i;
        Word w;
        w.letter = letter;
        w.col = wcol;
        double v = 0.0;
        bool dot = false;
        if (plain_number(i, v, dot)) {
          if (i < n && (p[i] == '.' || p[i] == '+' || p[i] == '-')) {
            // Marlin: an M code's parameter may be a version string (M115 U6.3.0+10073).
            bool after_m = false;
            for (int k = 0; k < out.count; ++k)
              after_m = after_m || out.words[static_cast<size_t>(k)].letter == 'M';
            if (!syn.macro_lines || !after_m)
              fail(col(i), fmt::format("garbage in the number of '{}'", letter));
            while (i < n && !is_space(p[i]) && p[i] != ';') ++i;
            w.bare = true;
          }
          w.value = v;
          w.integer = !dot;
        } else if (syn.ngc && i < n &&
                   (p[i] == '#' || p[i] == '[' || p[i] == '+' || p[i] == '-' ||
                    (is_alpha(p[i]) && expr().function_at(i)))) {
          w.value = expr().real_value(i);
          w.from_expr = true;
          w.integer = std::fabs(w.value - std::round(w.value)) <= detail::kIntegerTolerance;
        } else if (syn.macro_lines && i < n && p[i] == '"') {  // P "MK3S"
          int j = i + 1;
          while (j < n && p[j] != '"') ++j;
          if (j >= n) fail(col(i), "unterminated string '\"'");
          i = j + 1;
          w.bare = true;
          w.integer = true;
        } else if (syn.bare_letters && (i >= n || is_alpha(p[i]) || p[i] == '(' || p[i] == ';' ||
                                        p[i] == '*' || is_space(p[i]))) {
          w.bare = true;
          w.integer = true;
        } else {
          if (i < n && (non_printable(static_cast<unsigned char>(p[i])) ||
                        static_cast<unsigned char>(p[i]) >= 0x80 || p[i] == '#' || p[i] == '[')) {
            bad_char(i);
          }
          fail(wcol, fmt::format("expected a number after '{}'", letter));
        }
        push_word(out, w);
        if (letter == 'M' && syn.text_mcodes && w.integer && !w.bare && w.value >= 0 &&
            w.value < 10000 && is_text_mcode(static_cast<int>(w.value))) {
          const int code = static_cast<int>(w.value);
          int k = i;
          while (k < n && is_space(p[k])) ++k;
          const bool has_text = k < n && p[k] != ';' && p[k] != '*';
          if (code != 30 || has_text) {
            text_mcode(out, i);
            break;
          }
        }
        continue;
      }
      if (c == '(') {
        const int e = comment_end(i);
        last_comment = i;
        i = e + 1;
        continue;
      }
      if (c == ';' && syn.semicolon_comments) {
        check_rest_printable(i);
        break;
      }
      if (c == '*' && syn.checksums) {
        checksum(i);
        break;
      }
      if (c == '#' && syn.ngc) {
        assignment(i);
        continue;
      }
      if (c == '[' && syn.ngc) fail(col(i), "an expression '[...]' needs a word letter before it");
      bad_char(i);
    }
    apply_assignments();
    if (syn.ngc && last_comment >= 0) active_comment(out, last_comment);
    return true;
  }

  // '#<param> = <value>' at i.
  void assignment(int& i) {
    const int hcol = col(i);
    detail::Expr e = expr();
    ++i;
    Pending* slot = nullptr;
    if (npending == pending.size()) pending.emplace_back();
    slot = &pending[npending];
    if (i < n && p[i] == '<') {
      slot->index = 0;
      e.named_param(i, slot->name);
    } else {
      slot->index = e.param_index(i, hcol);
    }
    if (i >= n || p[i] != '=') {
      fail(hcol, "a parameter outside an expression must be assigned ('#1 = value')");
    }
    ++i;
    slot->value = e.real_value(i);
    ++npending;
  }

  void apply_assignments() {
    for (size_t k = 0; k < npending; ++k) {
      const Pending& a = pending[k];
      if (a.index > 0) {
        params.set(a.index, a.value);
      } else {
        params.set_named(a.name, a.value);
      }
    }
    npending = 0;
  }

  // (MSG,...), (DEBUG,...) and (PRINT,...): the line's last comment, keyword in any case,
  // directly followed by ','.
  void active_comment(Block& out, int i) {
    int k = i + 1;
    while (k < n && is_space(p[k])) ++k;
    static constexpr std::pair<std::string_view, MessageKind> kKinds[] = {
        {"MSG", MessageKind::kMsg}, {"DEBUG", MessageKind::kDebug}, {"PRINT", MessageKind::kPrint}};
    for (const auto& [kw, kind] : kKinds) {
      const int len = static_cast<int>(kw.size());
      if (k + len >= n || p[k + len] != ',') continue;
      bool match = true;
      for (int j = 0; j < len && match; ++j)
        match = to_upper(p[k + j]) == kw[static_cast<size_t>(j)];
      if (!match) continue;
      const int a = k + len + 1;
      int b = a;
      while (b < n && p[b] != ')') ++b;
      const size_t oa = static_cast<size_t>(col(a) - 1);
      const size_t ob = b > a ? static_cast<size_t>(col(b - 1)) : oa;
      const std::string_view body = orig.substr(oa, ob - oa);
      out.message_kind = kind;
      out.text_col = col(a);
      if (kind == MessageKind::kMsg) {
        out.text.assign(body);
      } else {
        substitute(body, out.text);
      }
      return;
    }
  }

  // DEBUG/PRINT text: '#n' and '#<name>' replaced by their values ('######' for an unset name),
  // formatted per the latest %d (0 decimals), %f (4), %.Nf (N), %lf (6, the default).
  void substitute(std::string_view s, std::string& outs) {
    int decimals = 6;
    size_t k = 0;
    while (k < s.size()) {
      const char c = s[k];
      if (c == '%') {
        if (k + 1 < s.size() && s[k + 1] == 'd') {
          decimals = 0;
          k += 2;
          continue;
        }
        if (k + 1 < s.size() && s[k + 1] == 'f') {
          decimals = 4;
          k += 2;
          continue;
        }
        if (k + 2 < s.size() && s[k + 1] == 'l' && s[k + 2] == 'f') {
          decimals = 6;
          k += 3;
          continue;
        }
        if (k + 3 < s.size() && s[k + 1] == '.' && is_digit(s[k + 2]) && s[k + 3] == 'f') {
          decimals = s[k + 2] - '0';
          k += 4;
          continue;
        }
      }
      if (c == '#' && k + 1 < s.size()) {
        if (s[k + 1] == '<') {
          const size_t close = s.find('>', k + 2);
          if (close != std::string_view::npos) {
            std::string name;
            for (size_t j = k + 2; j < close; ++j)
              if (!is_space(s[j])) name += to_lower(s[j]);
            const auto v = params.named(name);
            outs += v ? fmt::format("{:.{}f}", *v, decimals) : std::string("######");
            k = close + 1;
            continue;
          }
        } else if (is_digit(s[k + 1])) {
          size_t j = k + 1;
          int num = 0;
          while (j < s.size() && is_digit(s[j]) && num < Params::kCount)
            num = num * 10 + (s[j++] - '0');
          if (num >= 1 && num < Params::kCount) {
            outs += fmt::format("{:.{}f}", params.get(num), decimals);
            k = j;
            continue;
          }
        }
      }
      outs += c;
      ++k;
    }
  }

  // ---- O-words -------------------------------------------------------------------------------

  struct OLine {
    std::string label;
    Kw kw = Kw::kNone;
    int kw_col = 0;
    int label_col = 0;
    int args[kMaxArgs + 1][2] = {};  // [start, end) of each '[...]' argument in the buffer
    int nargs = 0;
  };

  // Parses the O-word at buffer index i (after the 'O').
  OLine parse_o(int i, int ocol) {
    OLine o;
    o.label_col = ocol;
    if (i < n && p[i] == '<') {
      int j = i + 1;
      o.label = "o<";
      while (j < n && p[j] != '>') o.label += to_lower(p[j++]);
      if (j >= n) fail(col(i), "unterminated O-word name '<'");
      if (j == i + 1) fail(col(i), "empty O-word name");
      o.label += '>';
      i = j + 1;
    } else if (i < n && is_digit(p[i])) {
      int j = i;
      while (j < n && is_digit(p[j])) ++j;
      if (j < n && p[j] == '.') fail(col(j), "an O-word number must be an integer");
      int z = i;
      while (z + 1 < j && p[z] == '0') ++z;
      o.label.assign(1, 'o');
      o.label.append(p + z, static_cast<size_t>(j - z));
      i = j;
    } else if (i < n && (p[i] == '[' || p[i] == '#')) {
      const double v = expr().real_value(i);
      if (std::fabs(v - std::round(v)) > detail::kIntegerTolerance || v < 0 || v > 1e9)
        fail(ocol, fmt::format("computed O-word number {} is not a non-negative integer", v));
      o.label = fmt::format("o{}", static_cast<long long>(std::round(v)));
      o.kw = Kw::kUnknown;  // marks the label as computed (checked below)
    } else {
      fail(ocol, "expected a number, <name> or [expression] after 'O'");
    }
    const bool computed = o.kw == Kw::kUnknown;
    const int kstart = i;
    int wend = i;
    while (wend < n && is_alpha(p[wend])) ++wend;
    const std::string_view word(p + i, static_cast<size_t>(wend - i));
    o.kw_col = kstart < n ? col(kstart) : col(n);
    size_t kwlen = 0;
    o.kw = keyword(word, kwlen);
    i += static_cast<int>(kwlen);
    if (o.kw == Kw::kUnknown) {
      fail(o.kw_col, fmt::format("unknown O-word keyword '{}' (sub, endsub, return, call, do, "
                                 "while, endwhile, if, elseif, else, endif, break, continue, "
                                 "repeat, endrepeat)",
                                 word));
    }
    if (computed && o.kw != Kw::kCall) {
      fail(ocol, "a computed O-word number ('o[...]') is only supported with call");
    }
    while (i < n && p[i] == '[') {
      if (o.nargs == kMaxArgs) fail(col(i), "more than 30 arguments");
      const int a = i;
      int depth = 0;
      for (; i < n; ++i) {
        if (p[i] == '[') ++depth;
        if (p[i] == ']' && --depth == 0) break;
        if (p[i] == '(' || p[i] == ';') break;
      }
      if (i >= n || p[i] != ']') fail(col(a), "unclosed '['");
      ++i;
      o.args[o.nargs][0] = a;
      o.args[o.nargs][1] = i;
      ++o.nargs;
    }
    while (i < n) {
      if (p[i] == '(') {
        i = comment_end(i) + 1;
        continue;
      }
      if (p[i] == ';' && syn.semicolon_comments) break;
      if (is_space(p[i])) {
        ++i;
        continue;
      }
      if (o.kw == Kw::kCall && p[i] != '[')
        fail(col(i), fmt::format("{} call: arguments must be in brackets, e.g. [1.5]", o.label));
      fail(col(i), fmt::format("unexpected '{}' after {} {}: an O-word line has no other words",
                               p[i], o.label, kw_name(o.kw)));
    }
    const auto need = [&](int lo, int hi, const char* what) {
      if (o.nargs < lo || o.nargs > hi)
        fail(o.kw_col, fmt::format("{} {} {}", o.label, kw_name(o.kw), what));
    };
    switch (o.kw) {
      case Kw::kIf:
      case Kw::kElseif:
      case Kw::kWhile:
        need(1, 1, "needs one condition in brackets, e.g. [#1 LT 10]");
        break;
      case Kw::kRepeat:
        need(1, 1, "needs one count in brackets, e.g. [5]");
        break;
      case Kw::kEndsub:
      case Kw::kReturn:
        need(0, 1, "takes at most one value in brackets");
        break;
      case Kw::kCall:
        break;
      case Kw::kNone:
        need(0, 0, "program number takes no arguments");
        break;
      default:
        need(0, 0, "takes no arguments");
    }
    return o;
  }

  double arg(const OLine& o, int k) {
    int i = o.args[k][0];
    const double v = expr().bracket(i);
    return v;
  }

  // Loads line `line0` for lexing (rs274ngc) and parses its O-word.
  OLine load_o(int line0) {
    orig = line_text(line0);
    lnum = line0 + 1;
    compact();
    int i = 0;
    if (i < n && p[i] == '/') ++i;
    if (i < n && p[i] == 'N') {
      ++i;
      while (i < n && (is_digit(p[i]) || p[i] == '.')) ++i;
    }
    return parse_o(i + 1, col(i));
  }

  void count_loop(int head_line, const std::string& label, Kw kw) {
    auto& loops = frames.back().loops;
    for (auto& [line, count] : loops) {
      if (line == head_line) {
        if (++count > loop_limit) {
          fail_at(head_line, 1,
                  fmt::format("{} {}: more than {} iterations (an endless loop?)", label,
                              kw_name(kw), loop_limit));
        }
        return;
      }
    }
    loops.emplace_back(head_line, 1);
  }
  void reset_loop(int head_line) {
    auto& loops = frames.back().loops;
    for (auto& [line, count] : loops)
      if (line == head_line) count = 0;
  }

  // Executes the O-word line `line0` (the current line); always returns false (no block).
  bool o_line(Block& out, int line0, int i, int ocol) {
    const OLine o = parse_o(i, ocol);
    const std::string& lab = o.label;
    auto missing = [&](const char* what) {
      fail(o.label_col, fmt::format("{} {} without {}", lab, kw_name(o.kw), what));
    };
    switch (o.kw) {
      case Kw::kNone:
        // 'O1000' alone: a program number (Fanuc style); nothing to do. Its N words stay.
        return true;
      case Kw::kSub: {
        const OEntry* e = find_after(lab, line0, {Kw::kEndsub});
        if (!e) missing("endsub");
        const OEntry* first = find_after(lab, -1, {Kw::kSub});
        if (first && first->line < line0) {
          fail(o.label_col,
               fmt::format("{} sub is defined twice (first at line {})", lab, first->line + 1));
        }
        cur = e->line + 1;
        return false;
      }
      case Kw::kEndsub:
      case Kw::kReturn: {
        if (frames.size() == 1) {
          fail(o.label_col, fmt::format("{} {} outside a subroutine call", lab, kw_name(o.kw)));
        }
        // A return may carry any label (LinuxCNC's retval.ngc returns with the label of the `if`
        // around it); endsub closes the subroutine it names.
        if (o.kw == Kw::kEndsub && frames.back().label != lab) {
          fail(o.label_col,
               fmt::format("{} {} inside subroutine {}", lab, kw_name(o.kw), frames.back().label));
        }
        const bool has_value = o.nargs == 1;
        const double v = has_value ? arg(o, 0) : 0.0;
        cur = frames.back().return_line;
        frames.pop_back();
        params.pop_frame();
        params.set_named("_value", v);
        params.set_named("_value_returned", has_value ? 1.0 : 0.0);
        out.kind = BlockKind::kReturn;
        return true;
      }
      case Kw::kCall: {
        const auto* es = entries(lab);
        const OEntry* def = nullptr;
        if (es) {
          for (const auto& e : *es) {
            if (e.kw != Kw::kSub) continue;
            if (def) {
              fail(o.label_col, fmt::format("{} sub is defined twice (lines {} and {})", lab,
                                            def->line + 1, e.line + 1));
            }
            def = &e;
          }
        }
        if (!def) {
          fail(o.label_col, fmt::format("subroutine {} is not defined in this file (subroutines in "
                                        "other files are not supported)",
                                        lab));
        }
        if (!find_after(lab, def->line, {Kw::kEndsub})) {
          fail_at(def->line, 1, fmt::format("{} sub without endsub", lab));
        }
        if (static_cast<int>(frames.size()) >= kMaxCallFrames) {
          fail(o.label_col, fmt::format("{} call: too many nested subroutine calls (at most {} "
                                        "levels, the main program included)",
                                        lab, kMaxCallFrames));
        }
        double args[kMaxArgs];
        for (int k = 0; k < o.nargs; ++k) args[k] = arg(o, k);
        params.set_named("_value", 0.0);
        params.set_named("_value_returned", 0.0);
        params.push_frame();
        for (int k = 0; k < o.nargs; ++k) params.set(k + 1, args[k]);
        Frame f;
        f.label = lab;
        f.call_line = lnum;
        f.return_line = line0 + 1;
        frames.push_back(std::move(f));
        cur = def->line + 1;
        out.kind = BlockKind::kCall;
        return true;
      }
      case Kw::kDo:
        if (!find_after(lab, line0, {Kw::kWhile}, true)) missing("a closing while");
        reset_loop(line0);
        return false;
      case Kw::kWhile: {
        const OEntry* self = find_after(lab, line0 - 1, {Kw::kWhile}, true);
        if (self && self->line == line0) {  // closes a 'do'
          if (arg(o, 0) != 0.0) {
            const OEntry* d = find_before(lab, line0, Kw::kDo);
            count_loop(d->line, lab, Kw::kDo);
            cur = d->line + 1;
          }
          return false;
        }
        const OEntry* end = find_after(lab, line0, {Kw::kEndwhile});
        if (!end) missing("endwhile");
        if (jumped_to != line0) reset_loop(line0);  // entered from above: a new loop
        jumped_to = -1;
        if (arg(o, 0) == 0.0) cur = end->line + 1;
        return false;
      }
      case Kw::kEndwhile: {
        const OEntry* head = find_before(lab, line0, Kw::kWhile);
        if (!head) missing("while");
        count_loop(head->line, lab, Kw::kWhile);
        jumped_to = head->line;
        cur = head->line;
        return false;
      }
      case Kw::kBreak:
      case Kw::kContinue: {
        const OEntry* end =
            find_after(lab, line0, {Kw::kEndwhile, Kw::kWhile, Kw::kEndrepeat}, true);
        if (!end || end->kw == Kw::kEndrepeat) {
          fail(o.label_col,
               fmt::format("{} {} outside a while or do loop of that number", lab, kw_name(o.kw)));
        }
        if (o.kw == Kw::kBreak) {
          cur = end->line + 1;
        } else {
          cur = end->line;  // endwhile jumps back to its while; a do's while tests again
        }
        return false;
      }
      case Kw::kIf: {
        if (!find_after(lab, line0, {Kw::kEndif})) missing("endif");
        if (arg(o, 0) != 0.0) return false;
        int at = line0;
        for (;;) {
          const OEntry* e = find_after(lab, at, {Kw::kElseif, Kw::kElse, Kw::kEndif});
          if (e->kw == Kw::kEndif || e->kw == Kw::kElse) {
            cur = e->line + 1;
            return false;
          }
          const OLine eo = load_o(e->line);  // elseif: test its condition
          if (arg(eo, 0) != 0.0) {
            cur = e->line + 1;
            return false;
          }
          at = e->line;
        }
      }
      case Kw::kElseif:
      case Kw::kElse: {
        if (!find_before(lab, line0, Kw::kIf)) missing("if");
        const OEntry* e = find_after(lab, line0, {Kw::kEndif});
        if (!e) fail(o.label_col, fmt::format("{} {} without endif", lab, kw_name(o.kw)));
        cur = e->line + 1;  // the branch before it ran: skip the rest
        return false;
      }
      case Kw::kEndif:
        if (!find_before(lab, line0, Kw::kIf)) missing("if");
        return false;
      case Kw::kRepeat: {
        const OEntry* end = find_after(lab, line0, {Kw::kEndrepeat});
        if (!end) missing("endrepeat");
        const double v = arg(o, 0);
        if (std::fabs(v) > 1e15) {
          fail(o.kw_col, fmt::format("{} repeat: count {} out of range", lab, v));
        }
        const auto times = static_cast<int64_t>(std::llround(v));
        auto& reps = frames.back().repeats;
        std::erase_if(reps, [&](const auto& r) { return r.first == line0; });
        if (times <= 0) {
          cur = end->line + 1;
        } else {
          reps.emplace_back(line0, times);
        }
        reset_loop(line0);
        return false;
      }
      case Kw::kEndrepeat: {
        const OEntry* head = find_before(lab, line0, Kw::kRepeat);
        if (!head) missing("repeat");
        auto& reps = frames.back().repeats;
        for (auto it = reps.begin(); it != reps.end(); ++it) {
          if (it->first != head->line) continue;
          if (--it->second > 0) {
            count_loop(head->line, lab, Kw::kRepeat);
            cur = head->line + 1;
          } else {
            reps.erase(it);
          }
          return false;
        }
        return false;
      }
      default:
        break;
    }
    (void)out;
    return false;
  }

  bool next(Block& out) {
    for (;;) {
      if (ended) return false;
      int line0 = 0;
      if (!fetch(line0)) {
        if (frames.size() > 1) {
          const Frame& f = frames.back();
          throw Error(file, f.call_line, 1,
                      fmt::format("end of file inside subroutine {} called here", f.label));
        }
        ended = true;
        return false;
      }
      if (lex(out, line0)) return true;
    }
  }
};

Reader::Reader(std::string file_name, std::string text, Syntax syntax, Params& params)
    : impl_(std::make_unique<Impl>(std::move(file_name), std::move(text), syntax, params)) {}

Reader::~Reader() = default;

bool Reader::next(Block& out) {
  return impl_->next(out);
}

void Reader::end_program() {
  impl_->ended = true;
}

void Reader::set_block_delete(bool on) {
  impl_->block_delete_on = on;
}

void Reader::set_loop_limit(uint64_t iterations) {
  impl_->loop_limit = iterations;
}

const std::string& Reader::file_name() const {
  return impl_->file;
}

std::vector<HeaderComment> header_comments(std::string_view text, int max_lines) {
  std::vector<HeaderComment> out;
  size_t a = 0;
  for (int line = 1; line <= max_lines && a < text.size(); ++line) {
    size_t e = text.find('\n', a);
    if (e == std::string_view::npos) e = text.size();
    const std::string_view s = text.substr(a, e - a);
    a = e + 1;
    auto add = [&](std::string_view t) {
      size_t x = 0, y = t.size();
      while (x < y && is_space(t[x])) ++x;
      while (y > x && is_space(t[y - 1])) --y;
      if (y > x) out.push_back(HeaderComment{line, std::string(t.substr(x, y - x))});
    };
    size_t k = 0;
    while (k < s.size()) {
      if (s[k] == '(') {  // nested parentheses are kept as text: "(Fusion 360 (grbl post))"
        size_t end = k + 1;
        int depth = 1;
        for (; end < s.size(); ++end) {
          if (s[end] == '(') ++depth;
          if (s[end] == ')' && --depth == 0) break;
        }
        add(s.substr(k + 1, end - k - 1));
        k = end + 1;
        continue;
      }
      if (s[k] == ';') {
        add(s.substr(k + 1));
        break;
      }
      ++k;
    }
  }
  return out;
}

}  // namespace fpgacnc::gcode
