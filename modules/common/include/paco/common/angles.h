#pragma once
// Usage:
//   double r = paco::degreesToRadians(10.0);   // 0.1745...
//   double d = paco::radiansToDegrees(paco::kPi / 4);  // 45
// One definition of pi for the whole library: M_PI is POSIX, not standard C++17.

namespace paco {

inline constexpr double kPi = 3.14159265358979323846;

constexpr double degreesToRadians(double degrees) { return degrees * (kPi / 180.0); }
constexpr double radiansToDegrees(double radians) { return radians * (180.0 / kPi); }

}  // namespace paco
