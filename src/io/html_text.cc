#include "io/html_text.h"

#include "io/base64.h"

namespace twinsim {

std::string HtmlEscape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else if (c == '&') out += "&amp;";
    else if (c == '"') out += "&quot;";
    else out += c;
  }
  return out;
}

std::string HtmlImage(const RgbaImage& image, const std::string& alt) {
  return "<img src=\"data:image/png;base64," + Base64Encode(EncodePng(image)) + "\" alt=\"" + HtmlEscape(alt) +
         "\" style=\"max-width:100%\">";
}

}  // namespace twinsim
