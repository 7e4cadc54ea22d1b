// Units of length and of plant area density, read from the text files give them.
#include "core/length_units.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <initializer_list>
#include <string>

namespace glaswave {
namespace {

std::string lower_trimmed(std::string_view text) {
  std::string u;
  for (char c : text) u += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  u.erase(0, u.find_first_not_of(" \t"));
  u.erase(u.find_last_not_of(" \t") + 1);
  return u;
}

}  // namespace

std::optional<double> metres_per_unit(std::string_view unit) {
  const std::string u = lower_trimmed(unit);
  const auto any = [&](std::initializer_list<const char*> names) {
    return std::find(names.begin(), names.end(), u) != names.end();
  };
  if (any({"", "m", "metre", "metres", "meter", "meters"})) return 1.0;
  if (any({"dm", "decimetre", "decimetres", "decimeter", "decimeters"})) return 0.1;
  if (any({"cm", "centimetre", "centimetres", "centimeter", "centimeters"})) return 0.01;
  if (any({"mm", "millimetre", "millimetres", "millimeter", "millimeters"})) return 0.001;
  if (any({"km", "kilometre", "kilometres", "kilometer", "kilometers"})) return 1000.0;
  if (any({"ft", "foot", "feet", "international foot", "international feet", "ft_i"}))
    return 0.3048;
  if (any({"us survey foot", "us survey feet", "ft-us", "us-ft", "ft_us", "us_ft", "foot_us",
           "survey foot", "us foot"}))
    return 1200.0 / 3937.0;
  return std::nullopt;
}

std::optional<double> per_metre_per_density_unit(std::string_view unit) {
  std::string u = lower_trimmed(unit);
  if (u.empty()) return 1.0;
  u.erase(std::remove(u.begin(), u.end(), '^'), u.end());
  double factor = 1.0;
  int power = 0, sign = 1;
  bool any_term = false;
  for (std::size_t at = 0; at < u.size();) {
    const char c = u[at];
    if (c == ' ' || c == '.' || c == '*') {
      ++at;
      continue;
    }
    if (c == '/') {  // what follows divides
      sign = -1;
      ++at;
      continue;
    }
    std::size_t end = at;
    while (end < u.size() && std::isalpha(static_cast<unsigned char>(u[end]))) ++end;
    const std::string name = u.substr(at, end - at);
    std::size_t digits = end;
    if (digits < u.size() && (u[digits] == '-' || u[digits] == '+')) ++digits;
    while (digits < u.size() && std::isdigit(static_cast<unsigned char>(u[digits]))) ++digits;
    const std::string exponent = u.substr(end, digits - end);
    if (digits == at) return std::nullopt;  // neither a name nor a number
    if (name.empty()) {                     // "1" of "1/m"
      if (exponent != "1") return std::nullopt;
    } else {
      const std::optional<double> metres = metres_per_unit(name);
      if (!metres || name.empty()) return std::nullopt;
      const int e = exponent.empty() || exponent == "+" || exponent == "-"
                        ? (exponent == "-" ? -1 : 1)
                        : std::stoi(exponent);
      if (std::abs(e) > 9) return std::nullopt;
      power += sign * e;
      factor *= std::pow(*metres, sign * e);
      any_term = true;
    }
    sign = 1;
    at = digits;
  }
  // m^-1 per unit: a length to the power -1, whose metres say how many m^-1 one unit is.
  if (!any_term || power != -1) return std::nullopt;
  return factor;
}

}  // namespace glaswave
