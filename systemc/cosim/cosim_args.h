// Command-line options of the co-simulation programs: `--name value` pairs. An unknown option or
// a missing value is an error (exit 2), so a mistyped option never silently runs the defaults.
// FPGACNC_SEED, when set, overrides --seed.
#pragma once

#include <fmt/format.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <map>
#include <string>

namespace fpgacnc::cosim {

class Options {
 public:
  explicit Options(std::string prog) : prog_(std::move(prog)) {}

  Options& u64(const std::string& name, uint64_t* v) {
    set_[name] = [v](const std::string& s) { *v = std::stoull(s); };
    return *this;
  }
  Options& size(const std::string& name, size_t* v) {
    set_[name] = [v](const std::string& s) { *v = static_cast<size_t>(std::stoull(s)); };
    return *this;
  }
  Options& real(const std::string& name, double* v) {
    set_[name] = [v](const std::string& s) { *v = std::stod(s); };
    return *this;
  }
  Options& flag(const std::string& name, bool* v) {
    set_[name] = [v](const std::string& s) { *v = s != "0"; };
    return *this;
  }

  // Returns false (after printing why) when the command line is not valid.
  bool parse(int argc, char* argv[]) const {
    for (int i = 1; i < argc; i += 2) {
      const std::string k = argv[i];
      const auto it = set_.find(k);
      if (it == set_.end()) {
        fmt::print(stderr, "{}: unknown option {}\n", prog_, k);
        return false;
      }
      if (i + 1 >= argc) {
        fmt::print(stderr, "{}: option {} needs a value\n", prog_, k);
        return false;
      }
      try {
        it->second(argv[i + 1]);
      } catch (const std::exception&) {
        fmt::print(stderr, "{}: bad value '{}' for {}\n", prog_, argv[i + 1], k);
        return false;
      }
    }
    return true;
  }

  // The seed in force (FPGACNC_SEED wins), printed so a failure can be reproduced.
  uint64_t seed(uint64_t seed, uint64_t seeds) const {
    if (const char* env = std::getenv("FPGACNC_SEED")) seed = std::strtoull(env, nullptr, 0);
    fmt::print("[seed] {}: {} (+0..{}; set FPGACNC_SEED to reproduce)\n", prog_, seed, seeds - 1);
    return seed;
  }

 private:
  std::string prog_;
  std::map<std::string, std::function<void(const std::string&)>> set_;
};

}  // namespace fpgacnc::cosim
