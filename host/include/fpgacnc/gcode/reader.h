// The reader: a program's text -> Blocks in execution order (block.h). It owns the lexical
// rules (comments, checksums, '%', '$' and '?' lines) and rs274ngc programming as LinuxCNC's
// documents define it: numbered and named parameters, expressions with LinuxCNC's operators and
// functions, assignments (applied after every parameter on the line has been read), and O-word
// subroutines and control flow (sub/endsub/call/return, if/elseif/else/endif, while/endwhile,
// do/while, repeat/endrepeat, break/continue).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "fpgacnc/gcode/block.h"
#include "fpgacnc/gcode/interpreter_error.h"

namespace fpgacnc::gcode {

// rs274ngc's parameter table. Numbered parameters 1..5602 (31..5000 global user parameters,
// 1..30 the subroutine arguments, local to a call; 5061-5069 probe, 5161-5169 G28 home,
// 5181-5189 G30 home, 5210-5219 G92, 5220 coordinate system, 5221-5390 G54-G59.3 offsets,
// 5399 M66 result, 5400-5413 tool, 5420-5428 current position): the interpreter writes the
// system ones as its state changes, programs read them. Named parameters: '#<name>' local to
// the subroutine call, '#<_name>' global. Unset parameters read as 0 (numbered) or are an error
// (named), as in LinuxCNC.
class Params {
 public:
  static constexpr int kCount = 5603;
  Params();
  double get(int n) const;  // n in [1, kCount); caller checks the range
  void set(int n, double value);
  std::optional<double> named(std::string_view name) const;  // name lower case, without <>
  void set_named(std::string_view name, double value);
  // Subroutine call frames (the reader uses these; 1..30 and local names are per frame).
  void push_frame();
  void pop_frame();

 private:
  std::vector<double> numbered_;
  std::map<std::string, double, std::less<>> globals_;
  std::vector<std::map<std::string, double, std::less<>>> locals_;
  std::vector<std::vector<double>> saved_args_;
};

class Reader {
 public:
  // `text` is the whole program (the reader keeps a copy: O-word loops and calls jump back).
  Reader(std::string file_name, std::string text, Syntax syntax, Params& params);
  ~Reader();
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;

  // Next block in execution order; false at the end of the program text. Every line that runs
  // gives one Block (blank and comment-only lines too, with no words), except O-word lines,
  // which the reader executes itself (a lone program number 'O1000' gives an empty Block, a call
  // a BlockKind::kCall Block and an endsub or return a BlockKind::kReturn one); a
  // line run again by a loop or call gives a Block again. Throws Error
  // ("FILE:LINE:COL: error: ...") for anything malformed: the error names the column of the
  // offending character, word or expression and says why.
  bool next(Block& out);

  // The interpreter calls this on M2/M30 (program end): the reader stops (next() returns false)
  // without reading the rest. Inside a subroutine this is still the end of the program.
  void end_program();

  // Block delete switch (off by default): when on, lines starting with '/' are skipped whole
  // (their words, assignments and O-words); when off they run and Block::block_delete is set.
  void set_block_delete(bool on);

  // Guard against endless O-word loops: a while, do or repeat loop that jumps back more than
  // this many times without being left is an error naming the loop's line (never a silent stop).
  static constexpr uint64_t kDefaultLoopLimit = 100'000'000;
  void set_loop_limit(uint64_t iterations);

  const std::string& file_name() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Reads the first `max_lines` lines of a program without interpreting them, for dialect
// detection: the comment texts in order (without '(' ')' or ';'), with their line numbers.
struct HeaderComment {
  int line = 0;
  std::string text;
};
std::vector<HeaderComment> header_comments(std::string_view text, int max_lines = 200);

}  // namespace fpgacnc::gcode
