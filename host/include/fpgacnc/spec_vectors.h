// Reader of spec/vectors.txt, the worked frames generated from spec/protocol.toml
// (scripts/gen_spec.py): the host codec test, the Verilated frame_decoder bench and the twin codec
// test all check their own codec against the same frames. Header-only, no dependencies.
//
// A vector is a block of lines "key value..." ending with "end" (format in the file's comment).
// Bad input throws std::runtime_error naming file:line:column and why.
#pragma once

#include <cstdint>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace fpgacnc::spec {

struct Vector {
  std::string name, doc;
  std::vector<uint8_t> bytes;  // the frame on the wire
  std::string type_name;       // "UNKNOWN" for a TYPE not in the table
  uint8_t type = 0;
  uint8_t seq = 0;
  std::map<std::string, std::vector<int64_t>> fields;  // decoded payload (a list for steps)
  // Host frames: the answer of a v2-mode device whose next_seq is `seq` (FIFO not full, 4 axes).
  bool has_answer = false;
  std::string answer;                                 // "ACK", "IDENT", "STATUS" or "NAK"
  std::string nak_name;                               // answer NAK: the reason's name
  uint8_t answer_value = 0;                           // the answer's TYPE, or the NAK reason
  std::map<std::string, std::vector<int64_t>> entry;  // the FIFO entry written (empty: none)

  bool has_entry() const { return !entry.empty(); }
  // One value of a field (`fallback` when absent).
  int64_t field(const std::string& k, int64_t fallback = 0) const {
    const auto it = fields.find(k);
    return it == fields.end() || it->second.empty() ? fallback : it->second.front();
  }
  std::vector<int64_t> list(const std::string& k) const {
    const auto it = fields.find(k);
    return it == fields.end() ? std::vector<int64_t>{} : it->second;
  }
  // An entry field, 0 when not named.
  int64_t entry_field(const std::string& k) const {
    const auto it = entry.find(k);
    return it == entry.end() || it->second.empty() ? 0 : it->second.front();
  }
  std::vector<int64_t> entry_steps() const {
    const auto it = entry.find("steps");
    return it == entry.end() ? std::vector<int64_t>{} : it->second;
  }
};

inline std::vector<Vector> load_vectors(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ":1:1: cannot open the vector file");
  std::vector<Vector> out;
  Vector cur;
  bool open = false;
  std::string line;
  int n = 0;
  auto fail = [&](size_t col, const std::string& why) {
    throw std::runtime_error(path + ":" + std::to_string(n) + ":" + std::to_string(col + 1) + ": " +
                             why);
  };
  while (std::getline(in, line)) {
    ++n;
    if (line.empty() || line[0] == '#') continue;
    const size_t sp = line.find(' ');
    const std::string key = line.substr(0, sp);
    const std::string rest = sp == std::string::npos ? "" : line.substr(sp + 1);
    const size_t rest_col = sp == std::string::npos ? line.size() : sp + 1;
    // Integers of `s` (starting at column `col` of the line).
    auto ints = [&](const std::string& s, size_t col, int base) {
      std::vector<int64_t> v;
      size_t i = 0;
      while (i < s.size()) {
        if (s[i] == ' ') {
          ++i;
          continue;
        }
        const size_t j = s.find(' ', i);
        const std::string tok = s.substr(i, j == std::string::npos ? std::string::npos : j - i);
        size_t used = 0;
        int64_t x = 0;
        try {
          x = std::stoll(tok, &used, base);
        } catch (const std::exception&) {
          used = 0;
        }
        if (used != tok.size()) fail(col + i, "not a number: \"" + tok + "\"");
        v.push_back(x);
        i += tok.size();
      }
      return v;
    };
    if (key == "vector") {
      if (open) fail(0, "\"vector\" inside vector " + cur.name + " (missing \"end\")");
      cur = Vector{};
      cur.name = rest;
      open = true;
      continue;
    }
    if (!open) fail(0, "\"" + key + "\" outside a vector");
    if (key == "end") {
      if (cur.bytes.empty()) fail(0, "vector " + cur.name + " has no bytes");
      out.push_back(cur);
      open = false;
    } else if (key == "doc") {
      cur.doc = rest;
    } else if (key == "bytes") {
      for (int64_t b : ints(rest, rest_col, 16)) {
        if (b < 0 || b > 0xFF) fail(rest_col, "byte out of range");
        cur.bytes.push_back(static_cast<uint8_t>(b));
      }
    } else if (key == "type" || key == "answer") {
      std::istringstream ss(rest);
      std::string name, extra;
      int value = -1;
      ss >> name;
      if (key == "answer" && name == "NAK") ss >> extra;
      ss >> value;
      if (name.empty() || value < 0 || value > 0xFF) fail(rest_col, "expected NAME VALUE");
      if (key == "type") {
        cur.type_name = name;
        cur.type = static_cast<uint8_t>(value);
      } else {
        cur.has_answer = true;
        cur.answer = name;
        cur.nak_name = extra;
        cur.answer_value = static_cast<uint8_t>(value);
      }
    } else if (key == "seq") {
      const auto v = ints(rest, rest_col, 10);
      if (v.size() != 1 || v[0] < 0 || v[0] > 0xFF) fail(rest_col, "expected one SEQ 0..255");
      cur.seq = static_cast<uint8_t>(v[0]);
    } else if (key == "field" || key == "entry") {
      const size_t sp2 = rest.find(' ');
      const std::string k = rest.substr(0, sp2);
      if (k.empty()) fail(rest_col, "expected NAME VALUE...");
      const std::string vals = sp2 == std::string::npos ? "" : rest.substr(sp2 + 1);
      (key == "field" ? cur.fields : cur.entry)[k] = ints(vals, rest_col + sp2 + 1, 10);
    } else {
      fail(0, "unknown key \"" + key + "\"");
    }
  }
  if (open) fail(0, "vector " + cur.name + " has no \"end\"");
  if (out.empty()) throw std::runtime_error(path + ":1:1: no vectors");
  return out;
}

#ifdef FPGACNC_SPEC_VECTORS
// The repository's spec/vectors.txt (path given by CMake).
inline std::vector<Vector> load_vectors() {
  return load_vectors(FPGACNC_SPEC_VECTORS);
}
#endif

}  // namespace fpgacnc::spec
