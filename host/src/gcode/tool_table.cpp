#include "fpgacnc/gcode/tool_table.h"

#include <fmt/format.h>

#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include "fpgacnc/gcode/interpreter_error.h"

namespace fpgacnc::gcode {

const ToolEntry* ToolTable::find(int tool) const {
  auto it = tools_.find(tool);
  return it == tools_.end() ? nullptr : &it->second;
}

void ToolTable::set(const ToolEntry& e) {
  tools_[e.tool] = e;
}

ToolTable parse_tool_table(std::string_view text, const std::string& name) {
  ToolTable t;
  int line = 0;
  size_t pos = 0;
  while (pos < text.size()) {
    size_t eol = text.find('\n', pos);
    if (eol == std::string_view::npos) eol = text.size();
    std::string_view l = text.substr(pos, eol - pos);
    pos = eol + 1;
    ++line;
    ToolEntry e;
    bool has_t = false;
    size_t i = 0;
    while (i < l.size()) {
      const char c = l[i];
      if (c == ' ' || c == '\t' || c == '\r') {
        ++i;
        continue;
      }
      if (c == ';') {
        size_t a = i + 1;
        while (a < l.size() && (l[a] == ' ' || l[a] == '\t')) ++a;
        size_t z = l.size();
        while (z > a && (l[z - 1] == ' ' || l[z - 1] == '\r')) --z;
        e.comment = std::string(l.substr(a, z - a));
        break;
      }
      const int col = static_cast<int>(i) + 1;
      const char letter = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
      ++i;
      size_t j = i;
      if (j < l.size() && (l[j] == '+' || l[j] == '-')) ++j;
      while (j < l.size() && (std::isdigit(static_cast<unsigned char>(l[j])) || l[j] == '.')) ++j;
      double v = 0.0;
      const char* first = l.data() + i + (i < l.size() && l[i] == '+' ? 1 : 0);
      auto r = std::from_chars(first, l.data() + j, v);
      if (j == i || r.ec != std::errc() || r.ptr != l.data() + j || !std::isfinite(v))
        throw Error(name, line, col, fmt::format("expected a number after '{}'", letter));
      i = j;
      switch (letter) {
        case 'T':
          e.tool = static_cast<int>(v);
          has_t = true;
          break;
        case 'P':
          e.pocket = static_cast<int>(v);
          break;
        case 'X':
          e.offset[0] = v;
          break;
        case 'Y':
          e.offset[1] = v;
          break;
        case 'Z':
          e.offset[2] = v;
          break;
        case 'D':
          e.diameter = v;
          break;
        case 'A':
        case 'B':
        case 'C':
        case 'U':
        case 'V':
        case 'W':
        case 'I':
        case 'J':
        case 'Q':
          break;  // rotary offsets, lathe angles and orientation: not used here
        default:
          throw Error(name, line, col, fmt::format("unknown tool table field '{}'", letter));
      }
    }
    if (!has_t) {
      const size_t first = l.find_first_not_of(" \t\r");
      if (first == std::string_view::npos || l[first] == ';') continue;
      throw Error(name, line, 1, "tool table line without T");
    }
    t.set(e);
  }
  return t;
}

ToolTable load_tool_table(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw Error(path, 0, 0, "cannot open tool table");
  std::ostringstream s;
  s << f.rdbuf();
  return parse_tool_table(s.str(), path);
}

}  // namespace fpgacnc::gcode
