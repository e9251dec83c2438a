// The number syntax of radmesh's text formats and the check that a
// third-party parser read a number as its text means (text_syntax.h).

#include "core/text_syntax.h"

#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <locale.h>

namespace radmesh::internal {

namespace {

bool digit(char c) { return c >= '0' && c <= '9'; }

// strtod in the "C" locale, whatever the program's: a locale whose decimal
// point is a comma would read "0.5" as 0.
double strtod_c(const char* text) {
  static const locale_t c_locale = newlocale(LC_NUMERIC_MASK, "C", static_cast<locale_t>(nullptr));
  return strtod_l(text, nullptr, c_locale);
}

bool contains_nocase(std::string_view text, const char* word) {
  const size_t n = std::strlen(word);
  for (size_t i = 0; i + n <= text.size(); ++i) {
    bool same = true;
    for (size_t k = 0; k < n && same; ++k) same = (text[i + k] | 0x20) == word[k];
    if (same) return true;
  }
  return false;
}

}  // namespace

std::string read_number(std::string_view t, double* value) {
  if (t.empty()) return "is empty";
  if (t.size() > kMaxNumberChars)
    return "is " + std::to_string(t.size()) + " characters long; radmesh reads numbers of at most " +
           std::to_string(kMaxNumberChars);
  if (t[0] == '+') return "starts with '+', which radmesh does not read (write the number without it)";
  const size_t sign = t[0] == '-' ? 1 : 0;
  size_t i = sign, digits = 0;
  while (i < t.size() && digit(t[i])) ++i, ++digits;
  if (i < t.size() && t[i] == '.') {
    ++i;
    while (i < t.size() && digit(t[i])) ++i, ++digits;
  }
  bool good = digits > 0;
  if (good && i < t.size() && (t[i] == 'e' || t[i] == 'E')) {
    ++i;
    if (i < t.size() && (t[i] == '+' || t[i] == '-')) ++i;
    size_t exponent_digits = 0;
    while (i < t.size() && digit(t[i])) ++i, ++exponent_digits;
    good = exponent_digits > 0;
  }
  if (!good || i != t.size()) {  // outside the syntax: say which way
    if (contains_nocase(t, "nan") || contains_nocase(t, "inf")) return "is not finite";
    if (t.size() > sign + 1 && t[sign] == '0' && (t[sign + 1] == 'x' || t[sign + 1] == 'X'))
      return "is hexadecimal, which radmesh does not read (write it in decimal)";
    if (t.find(',') != std::string_view::npos) return "is not a number (a comma is not a decimal point)";
    return "is not a number";
  }
  char text[kMaxNumberChars + 1];
  std::memcpy(text, t.data(), t.size());
  text[t.size()] = '\0';
  const double v = strtod_c(text);
  if (!std::isfinite(v)) return "is not finite (beyond the range of a double)";
  *value = v;
  return "";
}

std::string read_whole(std::string_view t, bool allow_negative, long long* value) {
  if (t.empty()) return "is empty";
  if (t[0] == '+') return "starts with '+', which radmesh does not read (write the number without it)";
  const bool negative = t[0] == '-';
  if (negative && !allow_negative) return "is negative";
  const size_t first = negative ? 1 : 0;
  if (t.size() == first) return "is not a whole number";
  for (size_t i = first; i < t.size(); ++i)
    if (!digit(t[i])) return "is not a whole number";
  if (t.size() - first > 18) return "has more than 18 digits";
  long long v = 0;
  for (size_t i = first; i < t.size(); ++i) v = 10 * v + (t[i] - '0');
  *value = negative ? -v : v;
  return "";
}

bool reads_as_double(double used, double meant) {
  return std::isfinite(used) && std::abs(used - meant) <= 1e-12 * std::abs(meant) + DBL_MIN;
}

bool reads_as_float(double used, double meant) {
  return std::isfinite(used) && std::abs(used - meant) <= 4e-6 * std::abs(meant) + FLT_MIN;
}

std::string shown(std::string_view text, size_t most) {
  std::string out;
  for (const char c : text.substr(0, most)) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u == 0x7f) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02X", static_cast<unsigned>(u));
      out += hex;
    } else {
      out += c;
    }
  }
  if (text.size() > most) out += "... (" + std::to_string(text.size()) + " characters)";
  return out;
}

bool strip_byte_order_mark(std::string& text) {
  if (text.rfind("\xEF\xBB\xBF", 0) != 0) return false;
  text.erase(0, 3);
  return true;
}

}  // namespace radmesh::internal
