// vds encoder: small text helpers the host readers share (names compared
// without case, a file's extension). Private to encoder/src.
#pragma once
#include <cctype>
#include <string>

namespace vds::enc {

// ASCII letters lowered; other bytes as they are.
inline std::string ascii_lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// The file name's extension, lower case, without the dot ("" if none).
inline std::string extension_of(const std::string& name) {
  const size_t dot = name.find_last_of('.');
  const size_t slash = name.find_last_of('/');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  return ascii_lower(name.substr(dot + 1));
}

}  // namespace vds::enc
