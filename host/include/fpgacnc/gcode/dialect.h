// G-code dialects: one table of the meanings that differ between controllers. Everything the
// dialects share is in the interpreter; a new dialect is a new row here (docs/gcode.md,
// "Dialects").
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "fpgacnc/gcode/block.h"

namespace fpgacnc::gcode {

enum class Dialect : uint8_t {
  kGrbl,      // grbl 1.1 and the CAM, laser and PCB programs that write for it
  kLinuxCnc,  // LinuxCNC's rs274ngc: parameters, expressions, O-words
  kMarlin,    // Marlin and the slicers that write for it (printers)
  kRepRap,    // RepRapFirmware (Duet) flavour of slicer output
  kMakerbot,  // MakerBot / Miracle-Grue / Skeinforge for MakerBot: the extruder is the A axis
};

struct DialectRules {
  Dialect dialect;
  const char* name;  // "grbl", "linuxcnc", "marlin", "reprap"
  Syntax syntax;
  bool dwell_p_ms;          // G4 P is milliseconds (S is seconds); else P is seconds
  bool g10_retract;         // G10/G11 without L are firmware retract/recover (with M207/M208)
  bool t_selects_extruder;  // T<n> selects an extruder (only T0 exists here), not a tool
  // An M code this interpreter does not know is skipped with a warning (Marlin answers
  // "Unknown command" and goes on); else it is an error.
  bool unknown_m_warns;
  bool g28_homes;  // G28 with bare axis letters homes those axes (Marlin); else rs274 G28
  bool e_is_axis;  // E words move the extruder (4th axis); LinuxCNC has no E word
  // A modal G2/G3 repeated with axis words but no centre runs as a straight cut (grbl senders
  // do this); LinuxCNC refuses it.
  bool modal_arc_as_line;
  bool feed_required;  // a G1/G2/G3 before any F is an error (LinuxCNC); else the default feed
  bool a_is_extruder;  // A words are the extruder (MakerBot)
  // M100..M199 (LinuxCNC's user M codes, vendors' extensions such as Mr Beam's compressor):
  // skipped with a warning; else an error like any unknown M code.
  bool user_m_warns;
  bool probing;  // G38.2 .. G38.5 are probe moves (grbl, LinuxCNC); else unknown G codes
};

const DialectRules& dialect_rules(Dialect d);
std::optional<Dialect> parse_dialect(std::string_view name);  // "grbl", "linuxcnc", ...
// "grbl, linuxcnc, marlin, reprap, makerbot" for messages.
const char* dialect_names();

// The dialect a program is in and why: an override (the command line or the machine
// configuration) wins; else the program's header comments name its generator (slicers, CAM and
// laser programs name themselves); else rs274ngc syntax ('#', 'O' words) makes it LinuxCNC;
// else Marlin signs (M82/M83, M104/M109, E words) make it Marlin; else grbl.
struct DialectChoice {
  Dialect dialect = Dialect::kGrbl;
  std::string reason;     // e.g. "line 1 names PrusaSlicer", "--dialect linuxcnc"
  std::string generator;  // the program named in the header, if any ("PrusaSlicer 2.7.1")
  // A CAM program that writes rs274ngc subroutines also writes '(' inside comments (Estlcam):
  // the linuxcnc dialect then keeps the CAM programs' comment rule.
  bool nested_comments = false;
};
DialectChoice detect_dialect(std::string_view text, std::optional<Dialect> override_dialect,
                             std::string_view override_source);

}  // namespace fpgacnc::gcode
