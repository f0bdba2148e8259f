// Protobuf's wire format written by hand, for tests that encode the league's and grSim's
// messages from their published field numbers rather than from the project's generated
// code: a client built from the official files sends these bytes.
#pragma once

#include <cstdint>
#include <string>

namespace twinsim::testing {

std::string Varint(std::uint64_t v);
// Field `field` as a varint (wire type 0: ints, bools, enums).
std::string VarintField(int field, std::uint64_t v);
// Field `field` length-delimited (wire type 2: strings, bytes, messages).
std::string BytesField(int field, const std::string& payload);
// Field `field` as a float (wire type 5) and a double (wire type 1), little-endian.
std::string FloatField(int field, float f);
std::string DoubleField(int field, double d);

}  // namespace twinsim::testing
