// Tool tables in LinuxCNC's format: one tool per line, "T<n> P<pocket> X.. Y.. Z.. D.. ;comment"
// (any of X Y Z D I J Q, in the machine's units, mm here); used by G43 H and M6 prompts.
#pragma once

#include <array>
#include <map>
#include <string>
#include <string_view>

namespace fpgacnc::gcode {

struct ToolEntry {
  int tool = 0;
  int pocket = 0;
  std::array<double, 3> offset{};  // X Y Z length offsets, mm
  double diameter = 0.0;
  std::string comment;
};

class ToolTable {
 public:
  const ToolEntry* find(int tool) const;
  void set(const ToolEntry& e);
  size_t size() const { return tools_.size(); }

 private:
  std::map<int, ToolEntry> tools_;
};

// Throws gcode::Error naming file:line:column for a malformed line.
ToolTable parse_tool_table(std::string_view text, const std::string& name);
ToolTable load_tool_table(const std::string& path);

}  // namespace fpgacnc::gcode
