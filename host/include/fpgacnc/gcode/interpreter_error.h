// The error every stage of the G-code front end throws.
#pragma once

#include "fpgacnc/error.h"

namespace fpgacnc::gcode {

// what(): "FILE:LINE:COL: error: MESSAGE", column of the offending word (1-based).
class Error : public SourceError {
 public:
  using SourceError::SourceError;
};

}  // namespace fpgacnc::gcode
