// The G-code front end's two stages meet here. The reader (reader.h) turns a program's text into
// Blocks in execution order: it strips comments, checks checksums, evaluates rs274ngc parameters,
// expressions and O-word control flow. The interpreter (interpreter.h) gives each Block's words
// their meaning in the job's dialect and produces machine commands.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>

namespace fpgacnc::gcode {

// One word after evaluation: letter A-Z (upper case), its value, where it was written.
struct Word {
  char letter = 0;
  double value = 0.0;
  int col = 0;             // 1-based column of the letter in the source line
  bool integer = true;     // written as a plain number without '.', or an expression whose
                           // value is within 1e-6 of an integer (LinuxCNC's rule for G/M codes)
  bool from_expr = false;  // the value came from a parameter or an expression
  bool bare = false;       // the letter had no number (Syntax::bare_letters); value is 0
};

// LinuxCNC's polar coordinates: '@' (distance) and '^' (angle, degrees) are words with these
// letters (Word::letter '@' and '^'); only with Syntax::ngc.
constexpr char kPolarRadius = '@';
constexpr char kPolarAngle = '^';

// What a line is, besides its words.
enum class BlockKind : uint8_t {
  kWords,    // an ordinary block (possibly with zero words: a comment or an assignment only)
  kPercent,  // a '%' program delimiter line (text after it is kept in `text`)
  kSystem,   // a grbl '$' line (`text` holds it from the '$'); only when Syntax::dollar_lines
  kQuery,    // a grbl '?' line; only when Syntax::dollar_lines
  kMacro,    // an extended command line ("START_PRINT", "EXCLUDE_OBJECT_DEFINE NAME=..."):
             // Klipper's, written by slicers; only when Syntax::macro_lines (`text` holds it)
  kCall,     // an O-word call line (rs274ngc): the subroutine's lines follow (no words)
  kReturn,   // an endsub or return line: the caller's lines follow (no words); M73 relies on it
};

// A message for the operator: (MSG,...), (DEBUG,...), (PRINT,...) comments (rs274ngc) and the
// text argument of Marlin's M117/M118 (Syntax::text_mcodes).
enum class MessageKind : uint8_t { kNone, kMsg, kDebug, kPrint, kText };

struct Block {
  static constexpr int kMaxWords = 64;
  int line = 0;  // 1-based line of the source file
  BlockKind kind = BlockKind::kWords;
  bool block_delete = false;  // the line started with '/' (the interpreter decides to skip)
  int count = 0;              // words[0..count)
  std::array<Word, kMaxWords> words{};
  MessageKind message_kind = MessageKind::kNone;
  std::string text;  // message text (parameters substituted for DEBUG/PRINT) or the
                     // '%' / '$' / '?' line's text
  int text_col = 0;  // column of the message or text

  const Word* find(char letter) const {
    for (int i = 0; i < count; ++i)
      if (words[static_cast<size_t>(i)].letter == letter) return &words[static_cast<size_t>(i)];
    return nullptr;
  }
};

// Lexical rules that differ between dialects (the dialect table in dialect.h fills one in).
struct Syntax {
  // rs274ngc programming: '#' parameters, '[...]' expressions, '#n=' assignments, O-words.
  // When false, '#', '[' and 'O' are refused with a message saying the dialect does not have them.
  bool ngc = false;
  // ';' starts a comment to the end of the line.
  bool semicolon_comments = true;
  // '(' inside a '(...)' comment is plain text (LinuxCNC refuses it; CAM programs write it).
  bool paren_in_comment = true;
  // 'N<n> ... *<cs>' checksums (Marlin/RepRap): verified and stripped.
  bool checksums = true;
  // M117, M118, M23, M28, M30 with text, M32, M928: the rest of the line after the M-code is text
  // (Block::text, MessageKind::kText), not words (Marlin/RepRap).
  bool text_mcodes = false;
  // '$' and '?' lines are grbl system commands (BlockKind::kSystem / kQuery), not errors.
  bool dollar_lines = false;
  // A letter followed by no number ('R' alone, 'G28 X Y' in Marlin) is kept with value 0 and
  // Word::col set; when false it is an error "expected a number after 'R'".
  bool bare_letters = false;
  // The dialect's name for error messages ("'#' parameters are rs274ngc (LinuxCNC) syntax; this
  // file's dialect is grbl"); empty: the messages say "not enabled for this file".
  const char* dialect_name = "";
  // A line that starts with a name of two or more letters, digits or '_' (Klipper's extended
  // commands) is BlockKind::kMacro; a word whose value is a "quoted string" (Marlin's M862.3
  // P "MK3S") is a bare word (Word::bare).
  bool macro_lines = false;
};

}  // namespace fpgacnc::gcode
