// Interim reader without rs274ngc programming (replaced by the full reader).
#include "fpgacnc/gcode/reader.h"

#include <fmt/format.h>

#include <charconv>
#include <cmath>

namespace fpgacnc::gcode {

Params::Params() : numbered_(kCount, 0.0) {}
double Params::get(int n) const { return numbered_[static_cast<size_t>(n)]; }
void Params::set(int n, double value) { numbered_[static_cast<size_t>(n)] = value; }
std::optional<double> Params::named(std::string_view name) const {
  auto it = globals_.find(name);
  if (it == globals_.end()) return std::nullopt;
  return it->second;
}
void Params::set_named(std::string_view name, double value) {
  globals_[std::string(name)] = value;
}
void Params::push_frame() {}
void Params::pop_frame() {}

struct Reader::Impl {
  std::string file;
  std::string text;
  Syntax syntax;
  size_t pos = 0;
  int line = 0;
  bool ended = false;
};

Reader::Reader(std::string file_name, std::string text, Syntax syntax, Params& params)
    : impl_(std::make_unique<Impl>()) {
  (void)params;
  impl_->file = std::move(file_name);
  impl_->text = std::move(text);
  impl_->syntax = syntax;
}
Reader::~Reader() = default;
void Reader::end_program() { impl_->ended = true; }
const std::string& Reader::file_name() const { return impl_->file; }

namespace {
bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r'; }
bool is_digit(char c) { return c >= '0' && c <= '9'; }
}  // namespace

bool Reader::next(Block& out) {
  Impl& m = *impl_;
  if (m.ended || m.pos >= m.text.size()) return false;
  size_t eol = m.text.find('\n', m.pos);
  if (eol == std::string::npos) eol = m.text.size();
  std::string_view text(m.text.data() + m.pos, eol - m.pos);
  m.pos = eol + 1;
  ++m.line;
  out.line = m.line;
  out.kind = BlockKind::kWords;
  out.block_delete = false;
  out.count = 0;
  out.message_kind = MessageKind::kNone;
  out.text.clear();
  out.text_col = 0;
  auto fail = [&](size_t i, const std::string& msg) {
    return Error(m.file, m.line, static_cast<int>(i) + 1, msg);
  };
  size_t star = std::string_view::npos;
  {
    bool in_paren = false, in_semi = false;
    for (size_t i = 0; i < text.size(); ++i) {
      const auto c = static_cast<unsigned char>(text[i]);
      if ((c < 0x20 && c != '\t' && c != '\r') || c == 0x7F)
        throw fail(i, fmt::format("non-printable byte 0x{:02X}", c));
      if (c >= 0x80 && !in_paren && !in_semi)
        throw fail(i, fmt::format("non-ASCII byte 0x{:02X}", c));
      if (in_semi) continue;
      if (in_paren) {
        if (c == ')') in_paren = false;
        continue;
      }
      if (c == '(') in_paren = true;
      if (c == ';' && m.syntax.semicolon_comments) in_semi = true;
      if (c == '*' && star == std::string_view::npos && m.syntax.checksums) star = i;
    }
  }
  if (star != std::string_view::npos) {
    unsigned x = 0;
    for (size_t i = 0; i < star; ++i) x ^= static_cast<unsigned char>(text[i]);
    size_t i = star + 1;
    unsigned given = 0;
    size_t digits = 0;
    while (i < text.size() && is_digit(text[i]) && digits < 4) {
      given = given * 10 + static_cast<unsigned>(text[i] - '0');
      ++i;
      ++digits;
    }
    size_t rest = i;
    while (rest < text.size() && is_space(text[rest])) ++rest;
    if (digits == 0 || given > 255 || (rest < text.size() && text[rest] != ';'))
      throw fail(star, "malformed checksum (expected *0..255)");
    if (given != x)
      throw fail(star, fmt::format("checksum mismatch: line says {}, computed {}", given, x));
    text = text.substr(0, star);
  }
  size_t i = 0;
  while (i < text.size() && is_space(text[i])) ++i;
  if (i < text.size() && text[i] == '%') {
    out.kind = BlockKind::kPercent;
    out.text = std::string(text.substr(i + 1));
    out.text_col = static_cast<int>(i) + 1;
    return true;
  }
  if (i < text.size() && (text[i] == '$' || text[i] == '?') && m.syntax.dollar_lines) {
    out.kind = text[i] == '$' ? BlockKind::kSystem : BlockKind::kQuery;
    out.text = std::string(text.substr(i));
    out.text_col = static_cast<int>(i) + 1;
    return true;
  }
  if (i < text.size() && text[i] == '/') {
    out.block_delete = true;
    ++i;
  }
  while (i < text.size()) {
    const char c = text[i];
    if (is_space(c)) {
      ++i;
      continue;
    }
    if (c == ';' && m.syntax.semicolon_comments) break;
    if (c == '(') {
      const size_t close = text.find(')', i);
      if (close == std::string_view::npos) throw fail(i, "unterminated comment '('");
      std::string_view body = text.substr(i + 1, close - i - 1);
      if (body.size() >= 4 && (body.substr(0, 4) == "MSG," || body.substr(0, 4) == "msg,")) {
        out.message_kind = MessageKind::kMsg;
        out.text = std::string(body.substr(4));
        out.text_col = static_cast<int>(i) + 1;
      }
      i = close + 1;
      continue;
    }
    const size_t col = i;
    char letter = c;
    if (letter >= 'a' && letter <= 'z') letter = static_cast<char>(letter - 'a' + 'A');
    if (letter < 'A' || letter > 'Z') throw fail(i, fmt::format("unexpected character '{}'", c));
    if (!m.syntax.ngc && (c == '#' || c == '[' || letter == 'O'))
      throw fail(i, "rs274ngc syntax needs the linuxcnc dialect");
    ++i;
    while (i < text.size() && is_space(text[i])) ++i;
    bool neg = false;
    if (i < text.size() && (text[i] == '+' || text[i] == '-')) {
      neg = text[i] == '-';
      ++i;
    }
    const size_t num_start = i;
    size_t ndig = 0;
    bool dot = false;
    while (i < text.size() && (is_digit(text[i]) || (text[i] == '.' && !dot))) {
      if (text[i] == '.')
        dot = true;
      else
        ++ndig;
      ++i;
    }
    if (out.count == Block::kMaxWords) throw fail(col, "too many words on one line");
    Word& w = out.words[static_cast<size_t>(out.count)];
    if (ndig == 0) {
      if (!m.syntax.bare_letters || neg || dot)
        throw fail(col, fmt::format("expected a number after '{}'", letter));
      w = Word{letter, 0.0, static_cast<int>(col) + 1, true, false, true};
      ++out.count;
      continue;
    }
    double v = 0.0;
    auto res = std::from_chars(text.data() + num_start, text.data() + i, v);
    if (res.ec != std::errc() || !std::isfinite(v))
      throw fail(col, fmt::format("invalid number for '{}'", letter));
    if (neg) v = -v;
    w = Word{letter, v, static_cast<int>(col) + 1, !dot, false, false};
    ++out.count;
    if (letter == 'M' && m.syntax.text_mcodes && !dot &&
        (v == 117 || v == 118 || v == 23 || v == 28 || v == 32 || v == 928)) {
      while (i < text.size() && is_space(text[i])) ++i;
      out.message_kind = MessageKind::kText;
      out.text = std::string(text.substr(i));
      out.text_col = static_cast<int>(i) + 1;
      break;
    }
  }
  return true;
}

std::vector<HeaderComment> header_comments(std::string_view text, int max_lines) {
  std::vector<HeaderComment> out;
  size_t pos = 0;
  for (int line = 1; line <= max_lines && pos < text.size(); ++line) {
    size_t eol = text.find('\n', pos);
    if (eol == std::string_view::npos) eol = text.size();
    std::string_view l = text.substr(pos, eol - pos);
    pos = eol + 1;
    for (size_t i = 0; i < l.size(); ++i) {
      if (l[i] == ';') {
        out.push_back({line, std::string(l.substr(i + 1))});
        break;
      }
      if (l[i] == '(') {
        size_t close = l.find(')', i);
        if (close == std::string_view::npos) close = l.size();
        out.push_back({line, std::string(l.substr(i + 1, close - i - 1))});
        i = close;
      }
    }
  }
  return out;
}

}  // namespace fpgacnc::gcode
