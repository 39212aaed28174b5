// fpgacnc subcommands: one file per subcommand, each registering itself on the CLI11 app.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <memory>
#include <string>

#include "fpgacnc/config/machine.h"
#include "fpgacnc/link/link.h"

namespace fpgacnc::cli {

// Options shared by subcommands that read a machine configuration.
struct CommonOptions {
  std::string config_path;          // --config
  double feed_override_pct = -1.0;  // --feed-override (negative: from config)
};

// Loads the configuration (defaults when no --config) and applies command-line overrides.
config::MachineConfig load_config(const CommonOptions& opt);

void register_plan(CLI::App& app);

// Hook for `stream` without --port: returns the link to use (e.g. start the simulated board).
// The default throws "no --port given and no simulated board built in".
using OpenDefaultLink = std::function<std::unique_ptr<link::Link>(const config::MachineConfig&)>;
struct StreamHooks {
  OpenDefaultLink open_default_link;
};
StreamHooks default_stream_hooks();
void register_stream(CLI::App& app, StreamHooks hooks);

}  // namespace fpgacnc::cli
