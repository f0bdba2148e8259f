#include "serve/protobuf_wire.h"

#include <cstring>

namespace twinsim::testing {
namespace {

std::string LittleEndian(std::uint64_t bits, int bytes) {
  std::string out;
  for (int k = 0; k < bytes; ++k) out.push_back(static_cast<char>((bits >> (8 * k)) & 0xff));
  return out;
}

}  // namespace

std::string Varint(std::uint64_t v) {
  std::string out;
  while (v >= 0x80) {
    out.push_back(static_cast<char>((v & 0x7f) | 0x80));
    v >>= 7;
  }
  out.push_back(static_cast<char>(v));
  return out;
}

std::string VarintField(int field, std::uint64_t v) { return Varint(static_cast<std::uint64_t>(field) << 3) + Varint(v); }

std::string BytesField(int field, const std::string& payload) {
  return Varint(static_cast<std::uint64_t>(field) << 3 | 2) + Varint(payload.size()) + payload;
}

std::string FloatField(int field, float f) {
  std::uint32_t bits;
  std::memcpy(&bits, &f, sizeof bits);
  return Varint(static_cast<std::uint64_t>(field) << 3 | 5) + LittleEndian(bits, 4);
}

std::string DoubleField(int field, double d) {
  std::uint64_t bits;
  std::memcpy(&bits, &d, sizeof bits);
  return Varint(static_cast<std::uint64_t>(field) << 3 | 1) + LittleEndian(bits, 8);
}

}  // namespace twinsim::testing
