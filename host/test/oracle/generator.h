// Deterministic generator of rs274ngc programs for the oracle test (docs/oracle.md): each family
// exercises one area of LinuxCNC's language with seeded random values, so that a feature our
// interpreter refuses shows up in its own programs and does not hide the others.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace fpgacnc::oracle {

struct GeneratedProgram {
  std::string name;  // "gen/<family>-<seed>"
  std::string text;
};

// The family names, in order.
std::vector<std::string> generator_families();

// One program of `family` from `seed` (same family and seed: same text, on every platform).
GeneratedProgram generate(const std::string& family, uint64_t seed);

// Every family with seeds 1..seeds_per_family.
std::vector<GeneratedProgram> generate_all(int seeds_per_family);

}  // namespace fpgacnc::oracle
