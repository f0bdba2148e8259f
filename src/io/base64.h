// Base64 (RFC 4648, with '=' padding): how self-contained HTML reports embed their PNGs
// as data: URIs, so that they read in a browser with no network and no side files.
//
//   html += "<img src=\"data:image/png;base64," + Base64Encode(EncodePng(image)) + "\">";
#pragma once

#include <string>

namespace twinsim {

// The base64 text of `bytes`.
std::string Base64Encode(const std::string& bytes);

}  // namespace twinsim
