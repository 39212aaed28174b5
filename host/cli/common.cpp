#include "fpgacnc/config/machine.h"

#include "commands.h"

namespace fpgacnc::cli {

config::MachineConfig load_config(const CommonOptions& opt) {
  config::MachineConfig cfg;
  if (!opt.config_path.empty()) cfg = config::load_machine_config(opt.config_path);
  if (opt.feed_override_pct >= 0.0) {
    cfg.feed_override_pct = opt.feed_override_pct;
    config::validate(cfg, "--feed-override");
  }
  return cfg;
}

}  // namespace fpgacnc::cli
