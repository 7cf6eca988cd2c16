// Small text helpers shared by the pipeline's parsing and messages.
#ifndef MJTOUCH_PIPELINE_TEXT_H_
#define MJTOUCH_PIPELINE_TEXT_H_

#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

namespace mjtouch {

inline std::string Trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t\n\r");
  if (a == std::string::npos) return "";
  const size_t b = s.find_last_not_of(" \t\n\r");
  return s.substr(a, b - a + 1);
}

inline std::vector<std::string> Words(const std::string& s) {
  std::istringstream ss(s);
  std::vector<std::string> out;
  std::string w;
  while (ss >> w) out.push_back(w);
  return out;
}

inline std::string Fmt(const char* fmt, ...) __attribute__((format(printf, 1, 2)));
inline std::string Fmt(const char* fmt, ...) {
  char buf[512];
  va_list ap;
  va_start(ap, fmt);
  std::vsnprintf(buf, sizeof(buf), fmt, ap);
  va_end(ap);
  return buf;
}

// A whole word as a finite number.
inline bool ToDouble(const std::string& w, double* v) {
  const char* s = w.c_str();
  char* end = nullptr;
  *v = std::strtod(s, &end);
  return end != s && *end == '\0' && std::isfinite(*v);
}

}  // namespace mjtouch

#endif  // MJTOUCH_PIPELINE_TEXT_H_
