// The original controller's step file (CSV): first line a header; columns (0-based) 0 segment
// number, 2 motion code, 5 steps X, 6 steps Y, 8 feed (decimal, rounded); >= 9 columns.
#pragma once

#include <iosfwd>
#include <string>

#include "fpgacnc/error.h"
#include "fpgacnc/plan/planner.h"

namespace fpgacnc::plan {

class StepFileError : public SourceError {
 public:
  using SourceError::SourceError;
};

// Reads a step file into segments (source_line = CSV line number, targets accumulated).
Plan read_step_file(std::istream& in, const std::string& name, const config::MachineConfig& cfg);
Plan read_step_file(const std::string& path, const config::MachineConfig& cfg);

// Writes a step file: header "segment,line,motion,x_mm,y_mm,steps_x,steps_y,length_mm,feed,
// feed_mm_min,steps_z,steps_e"; x_mm/y_mm are the absolute target. Only segments are written.
void write_step_file(std::ostream& out, const Plan& plan, const config::MachineConfig& cfg);
void write_step_file(const std::string& path, const Plan& plan, const config::MachineConfig& cfg);

// True when the path ends in ".csv" (any case) or the first line looks like a CSV header.
bool looks_like_step_file(const std::string& path);

}  // namespace fpgacnc::plan
