// Reader of spec/vectors.txt, the worked frames and sequences generated from spec/protocol.toml
// (scripts/gen_spec.py): the host codec test, the Verilated frame_decoder, response_encoder and
// cnc_core benches and the twin tests all check their own codec against the same frames.
// Header-only, no dependencies.
//
// A vector is a block of lines "key value..." ending with "end"; so is a sequence (host frames
// sent back to back and every device frame that comes back). Format in the file's comment.
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

// A worked sequence: from a device just out of reset (auto mode, next_seq 0, FIFO empty, the
// default board) the host frames are sent back to back at the device's baud with no idle time;
// the replies are every device frame that comes back, in order.
struct SeqReply {
  std::string type_name;
  uint8_t type = 0;
  std::vector<uint8_t> bytes;             // the device frame on the wire
  std::map<std::string, int64_t> fields;  // NAK seq, reason, next_seq, free; IDENT next_seq...
  int64_t field(const std::string& k, int64_t fallback = -1) const {
    const auto it = fields.find(k);
    return it == fields.end() ? fallback : it->second;
  }
};
struct SeqFrame {
  std::string vector;  // the vector whose frame this is
  std::vector<uint8_t> bytes;
};
struct Sequence {
  std::string name, doc;
  std::vector<SeqFrame> sends;
  std::vector<SeqReply> replies;
  // Every host byte in order (what goes on rx), every device byte in order (what comes on tx).
  std::vector<uint8_t> host_bytes() const {
    std::vector<uint8_t> b;
    for (const auto& f : sends) b.insert(b.end(), f.bytes.begin(), f.bytes.end());
    return b;
  }
  std::vector<uint8_t> device_bytes() const {
    std::vector<uint8_t> b;
    for (const auto& r : replies) b.insert(b.end(), r.bytes.begin(), r.bytes.end());
    return b;
  }
};

struct SpecFile {
  std::vector<Vector> vectors;
  std::vector<Sequence> sequences;
};

inline SpecFile load_spec_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ":1:1: cannot open the vector file");
  SpecFile file;
  std::vector<Vector>& out = file.vectors;
  Vector cur;
  Sequence seq;
  enum class Block { kVector, kSequence } block = Block::kVector;
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
    auto hex = [&](const std::string& s, size_t col) {
      std::vector<uint8_t> b;
      for (int64_t x : ints(s, col, 16)) {
        if (x < 0 || x > 0xFF) fail(col, "byte out of range");
        b.push_back(static_cast<uint8_t>(x));
      }
      if (b.empty()) fail(col, "expected bytes");
      return b;
    };
    const std::string open_name = block == Block::kSequence ? seq.name : cur.name;
    if (key == "vector" || key == "sequence") {
      if (open) fail(0, "\"" + key + "\" inside " + open_name + " (missing \"end\")");
      if (key == "vector") {
        cur = Vector{};
        cur.name = rest;
        block = Block::kVector;
      } else {
        seq = Sequence{};
        seq.name = rest;
        block = Block::kSequence;
      }
      open = true;
      continue;
    }
    if (!open) fail(0, "\"" + key + "\" outside a vector or sequence");
    if (block == Block::kSequence) {
      // NAME then the rest of the line at its column.
      auto split = [&](std::string& name, std::string& tail, size_t& tail_col) {
        const size_t sp2 = rest.find(' ');
        name = rest.substr(0, sp2);
        if (name.empty() || sp2 == std::string::npos) fail(rest_col, "expected NAME VALUE...");
        tail = rest.substr(sp2 + 1);
        tail_col = rest_col + sp2 + 1;
      };
      std::string name, tail;
      size_t tail_col = 0;
      if (key == "end") {
        if (seq.sends.empty()) fail(0, "sequence " + seq.name + " sends nothing");
        file.sequences.push_back(seq);
        open = false;
      } else if (key == "doc") {
        seq.doc = rest;
      } else if (key == "send") {
        split(name, tail, tail_col);
        seq.sends.push_back(SeqFrame{name, hex(tail, tail_col)});
      } else if (key == "reply") {
        split(name, tail, tail_col);
        SeqReply r;
        r.type_name = name;
        const size_t sp3 = tail.find(' ');
        const auto v = ints(tail.substr(0, sp3), tail_col, 10);
        if (v.size() != 1 || v[0] < 0 || v[0] > 0xFF || sp3 == std::string::npos)
          fail(tail_col, "expected TYPE VALUE HEX...");
        r.type = static_cast<uint8_t>(v[0]);
        r.bytes = hex(tail.substr(sp3 + 1), tail_col + sp3 + 1);
        seq.replies.push_back(r);
      } else if (key == "rfield") {
        if (seq.replies.empty()) fail(0, "\"rfield\" before a \"reply\"");
        split(name, tail, tail_col);
        const auto v = ints(tail, tail_col, 10);
        if (v.size() != 1) fail(tail_col, "expected one value");
        seq.replies.back().fields[name] = v[0];
      } else {
        fail(0, "unknown key \"" + key + "\" in a sequence");
      }
      continue;
    }
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
  if (open)
    fail(0, (block == Block::kSequence ? "sequence " + seq.name : "vector " + cur.name) +
                " has no \"end\"");
  if (out.empty()) throw std::runtime_error(path + ":1:1: no vectors");
  return file;
}

inline std::vector<Vector> load_vectors(const std::string& path) {
  return load_spec_file(path).vectors;
}
inline std::vector<Sequence> load_sequences(const std::string& path) {
  return load_spec_file(path).sequences;
}

#ifdef FPGACNC_SPEC_VECTORS
// The repository's spec/vectors.txt (path given by CMake).
inline std::vector<Vector> load_vectors() {
  return load_vectors(FPGACNC_SPEC_VECTORS);
}
inline std::vector<Sequence> load_sequences() {
  return load_sequences(FPGACNC_SPEC_VECTORS);
}
#endif

}  // namespace fpgacnc::spec
