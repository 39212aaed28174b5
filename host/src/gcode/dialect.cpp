#include "fpgacnc/gcode/dialect.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cstring>

#include "fpgacnc/gcode/reader.h"

namespace fpgacnc::gcode {
namespace {

constexpr Syntax kCamSyntax{.ngc = false,
                            .semicolon_comments = true,
                            .paren_in_comment = true,
                            .checksums = true,
                            .text_mcodes = false,
                            .dollar_lines = true,
                            .bare_letters = false};
constexpr Syntax kNgcSyntax{.ngc = true,
                            .semicolon_comments = true,
                            .paren_in_comment = false,
                            .checksums = false,
                            .text_mcodes = false,
                            .dollar_lines = false,
                            .bare_letters = false};
constexpr Syntax kPrinterSyntax{.ngc = false,
                                .semicolon_comments = true,
                                .paren_in_comment = true,
                                .checksums = true,
                                .text_mcodes = true,
                                .dollar_lines = false,
                                .bare_letters = true,
                                .macro_lines = true};

// The table of meanings (docs/gcode.md, "Dialects").
// Columns: dwell P in ms, G10 retract, T = extruder, unknown M warns, G28 homes, E is an axis,
// modal arc as line, feed required, A is the extruder, M100-M199 warn, G38.x probes.
constexpr std::array<DialectRules, 5> kRules{{
    {Dialect::kGrbl, "grbl", kCamSyntax, false, false, false, false, false, true, true, false,
     false, true, true},
    {Dialect::kLinuxCnc, "linuxcnc", kNgcSyntax, false, false, false, false, false, false, false,
     true, false, false, true},
    {Dialect::kMarlin, "marlin", kPrinterSyntax, true, true, true, true, true, true, true, false,
     false, true, false},
    {Dialect::kRepRap, "reprap", kPrinterSyntax, true, true, true, true, true, true, true, false,
     false, true, false},
    {Dialect::kMakerbot, "makerbot", kPrinterSyntax, true, true, true, true, true, true, true,
     false, true, true, false},
}};

std::string lower(std::string_view s) {
  std::string r(s);
  for (auto& c : r) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return r;
}

struct Generator {
  const char* needle;  // lower case, searched in header comments
  const char* name;
  Dialect dialect;
};

// Programs that name themselves in their first comments. Slicers write for printers (Marlin
// unless the file says RepRap); CAM, laser and PCB programs for grbl-like controllers unless
// they say LinuxCNC.
constexpr std::array<Generator, 49> kGenerators{{
    {"creality_print", "Creality Print", Dialect::kMarlin},
    {"creality print", "Creality Print", Dialect::kMarlin},
    {"miracle-grue", "Miracle-Grue", Dialect::kMakerbot},
    {"makerbot", "MakerBot", Dialect::kMakerbot},
    {"replicatorg", "ReplicatorG", Dialect::kMakerbot},
    {"flavor:reprap", "Cura (RepRap flavour)", Dialect::kRepRap},
    {"reprapfirmware", "RepRapFirmware", Dialect::kRepRap},
    {"flavor:marlin", "Cura (Marlin flavour)", Dialect::kMarlin},
    {"flavor:griffin", "Cura (Griffin flavour)", Dialect::kMarlin},
    {"cura_steamengine", "Cura", Dialect::kMarlin},
    {"prusaslicer", "PrusaSlicer", Dialect::kMarlin},
    {"superslicer", "SuperSlicer", Dialect::kMarlin},
    {"orcaslicer", "OrcaSlicer", Dialect::kMarlin},
    {"bambustudio", "BambuStudio", Dialect::kMarlin},
    {"slic3r", "Slic3r", Dialect::kMarlin},
    {"simplify3d", "Simplify3D", Dialect::kMarlin},
    {"ideamaker", "ideaMaker", Dialect::kMarlin},
    {"kisslicer", "KISSlicer", Dialect::kMarlin},
    {"mattercontrol", "MatterControl", Dialect::kMarlin},
    {"craftware", "CraftWare", Dialect::kMarlin},
    {"skeinforge", "Skeinforge", Dialect::kMarlin},
    {"kiri:moto", "Kiri:Moto", Dialect::kGrbl},  // FDM output says so below (M82/M104)
    {"linuxcnc", "LinuxCNC", Dialect::kLinuxCnc},
    {"emc2", "EMC2", Dialect::kLinuxCnc},
    {"fusion 360", "Fusion 360", Dialect::kGrbl},
    {"autodesk", "Autodesk CAM", Dialect::kGrbl},
    {"estlcam", "Estlcam", Dialect::kGrbl},
    {"carveco", "Carveco", Dialect::kGrbl},
    {"vcarve", "VCarve", Dialect::kGrbl},
    {"aspire", "Aspire", Dialect::kGrbl},
    {"vectric", "Vectric", Dialect::kGrbl},
    {"carbide create", "Carbide Create", Dialect::kGrbl},
    {"jscut", "jscut", Dialect::kGrbl},
    {"openbuilds", "OpenBuilds CAM", Dialect::kGrbl},
    {"flatcam", "FlatCAM", Dialect::kGrbl},
    {"pcb2gcode", "pcb2gcode", Dialect::kGrbl},
    {"eagle", "Eagle", Dialect::kGrbl},
    {"gcodetools", "Inkscape gcodetools", Dialect::kGrbl},
    {"inkscape", "Inkscape", Dialect::kGrbl},
    {"j tech", "J Tech laser tool", Dialect::kGrbl},
    {"laserweb", "LaserWeb", Dialect::kGrbl},
    {"lightburn", "LightBurn", Dialect::kGrbl},
    {"lasergrbl", "LaserGRBL", Dialect::kGrbl},
    {"bcnc", "bCNC", Dialect::kGrbl},
    {"easel", "Easel", Dialect::kGrbl},
    {"makercam", "MakerCAM", Dialect::kGrbl},
    {"freecad", "FreeCAD", Dialect::kGrbl},
    {"kicad", "KiCad", Dialect::kGrbl},
    {"grbl", "grbl", Dialect::kGrbl},
}};

// First line (1-based) where `pred` holds for a line's text outside comments, or 0.
template <typename Pred>
int first_code_line(std::string_view text, int max_lines, Pred pred) {
  size_t pos = 0;
  for (int line = 1; line <= max_lines && pos < text.size(); ++line) {
    size_t eol = text.find('\n', pos);
    if (eol == std::string_view::npos) eol = text.size();
    std::string_view l = text.substr(pos, eol - pos);
    pos = eol + 1;
    const size_t semi = l.find(';');
    if (semi != std::string_view::npos) l = l.substr(0, semi);
    std::string code;
    bool paren = false;
    for (char c : l) {
      if (paren) {
        paren = c != ')';
        continue;
      }
      if (c == '(') {
        paren = true;
        continue;
      }
      if (c != ' ' && c != '\t' && c != '\r')
        code += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    }
    if (!code.empty() && pred(std::string_view(code))) return line;
  }
  return 0;
}

// True when text[at] is outside '(...)' and ';' comments of its line (line starts at `from`).
bool outside_comment(std::string_view text, size_t from, size_t at) {
  bool paren = false;
  for (size_t i = from; i < at; ++i) {
    const char c = text[i];
    if (paren) {
      paren = c != ')';
    } else if (c == '(') {
      paren = true;
    } else if (c == ';') {
      return false;
    }
  }
  return !paren;
}

// First line with rs274ngc syntax outside comments ('#', '[', '@', '^', or an O-word: 'O' or
// 'o' first on its line, after an optional N word, followed by a digit or '<'), or 0. It runs on
// every file: memchr finds the candidates, only their lines are looked at.
int first_ngc_line(std::string_view text) {
  size_t best = text.size();
  for (const char sym : {'#', '[', '@', '^'}) {
    size_t from = 0;
    while (from < best) {
      const void* hit = std::memchr(text.data() + from, sym, best - from);
      if (!hit) break;
      const size_t at = static_cast<size_t>(static_cast<const char*>(hit) - text.data());
      const size_t nl = text.rfind('\n', at);
      const size_t line_start = nl == std::string_view::npos ? 0 : nl + 1;
      if (outside_comment(text, line_start, at)) {
        best = at;
        break;
      }
      from = at + 1;
    }
  }
  // O-words: the first word of a line (after an optional N word).
  for (size_t ls = 0; ls < best;) {
    size_t i = ls;
    while (i < text.size() && (text[i] == ' ' || text[i] == '\t')) ++i;
    if (i < text.size() && (text[i] == 'N' || text[i] == 'n')) {
      ++i;
      while (i < text.size() && std::isdigit(static_cast<unsigned char>(text[i]))) ++i;
      while (i < text.size() && (text[i] == ' ' || text[i] == '\t')) ++i;
    }
    if (i + 1 < text.size() && (text[i] == 'O' || text[i] == 'o') &&
        (text[i + 1] == '<' || std::isdigit(static_cast<unsigned char>(text[i + 1])))) {
      best = std::min(best, i);
      break;
    }
    const void* nl = std::memchr(text.data() + ls, '\n', text.size() - ls);
    if (!nl) break;
    ls = static_cast<size_t>(static_cast<const char*>(nl) - text.data()) + 1;
  }
  if (best >= text.size()) return 0;
  return 1 +
         static_cast<int>(std::count(text.begin(), text.begin() + static_cast<long>(best), '\n'));
}

bool starts_with_word(std::string_view code, std::string_view word) {
  // `code` has no spaces and is upper case; the word must not continue with a digit.
  size_t at = 0;
  while (true) {
    const size_t p = code.find(word, at);
    if (p == std::string_view::npos) return false;
    const size_t end = p + word.size();
    const bool digit_before =
        p > 0 && (std::isdigit(static_cast<unsigned char>(code[p - 1])) || code[p - 1] == '.');
    const bool digit_after =
        end < code.size() &&
        (std::isdigit(static_cast<unsigned char>(code[end])) || code[end] == '.');
    if (!digit_before && !digit_after) return true;
    at = p + 1;
  }
}

}  // namespace

const DialectRules& dialect_rules(Dialect d) {
  return kRules[static_cast<size_t>(d)];
}

const char* dialect_names() {
  return "grbl, linuxcnc, marlin, reprap, makerbot";
}

std::optional<Dialect> parse_dialect(std::string_view name) {
  const std::string n = lower(name);
  for (const auto& r : kRules)
    if (n == r.name) return r.dialect;
  if (n == "rs274ngc") return Dialect::kLinuxCnc;
  if (n == "reprapfirmware" || n == "rrf") return Dialect::kRepRap;
  return std::nullopt;
}

DialectChoice detect_dialect(std::string_view text, std::optional<Dialect> override_dialect,
                             std::string_view override_source) {
  DialectChoice c;
  constexpr int kScan = 400;  // lines read for the detection
  const auto comments = header_comments(text, kScan);
  for (const auto& hc : comments) {
    const std::string t = lower(hc.text);
    for (const auto& g : kGenerators) {
      if (t.find(g.needle) == std::string::npos) continue;
      c.generator = g.name;
      c.dialect = g.dialect;
      c.reason = fmt::format("line {} names {}", hc.line, g.name);
      break;
    }
    if (!c.generator.empty()) break;
  }
  // rs274ngc programming in the text makes it LinuxCNC whatever wrote it.
  const int ngc_line = first_ngc_line(text);
  const bool printer_generator =
      !c.generator.empty() && (c.dialect == Dialect::kMarlin || c.dialect == Dialect::kRepRap);
  if (override_dialect) {
    c.dialect = *override_dialect;
    c.reason = fmt::format("{} {}", override_source, dialect_rules(c.dialect).name);
    return c;
  }
  if (ngc_line && !printer_generator) {
    const bool cam = !c.generator.empty() && c.dialect == Dialect::kGrbl;
    c.dialect = Dialect::kLinuxCnc;
    c.reason = fmt::format("line {} uses rs274ngc parameters, expressions or O-words", ngc_line);
    if (cam) {
      c.nested_comments = true;
      c.reason += fmt::format(" ({} writes them; its comments may nest)", c.generator);
    }
    return c;
  }
  // Printer signs: extrusion mode, heaters, E words on moves.
  const int printer_line = first_code_line(text, kScan, [](std::string_view code) {
    return starts_with_word(code, "M82") || starts_with_word(code, "M83") ||
           starts_with_word(code, "M104") || starts_with_word(code, "M109") ||
           starts_with_word(code, "M140") || starts_with_word(code, "M190") ||
           ((code.starts_with("G1") || code.starts_with("G0")) &&
            code.find('E') != std::string_view::npos);
  });
  if (printer_line && (c.generator.empty() || c.dialect == Dialect::kGrbl)) {
    c.dialect = Dialect::kMarlin;
    c.reason =
        c.generator.empty()
            ? fmt::format("line {} has printer codes (extrusion or heaters)", printer_line)
            : fmt::format("{} wrote it and line {} has printer codes", c.generator, printer_line);
    return c;
  }
  if (!c.generator.empty()) return c;
  c.dialect = Dialect::kGrbl;
  c.reason = "no program named in the header and no printer or rs274ngc codes (the default)";
  return c;
}

}  // namespace fpgacnc::gcode
