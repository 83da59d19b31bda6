#pragma once
// Usage:
//   if (cloud.empty()) throw paco::InvalidInputError("PlanarSegmenter: input cloud is empty; set one with setInputCloud()");
//   try { ... } catch (const paco::Error& e) { std::cerr << e.what(); }
#include <stdexcept>
#include <string>

namespace paco {

/// Base class of every error paco throws. The message says what is wrong, where, and what to do.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Bad input given to an algorithm: empty cloud, NaN coordinates, too few planes, bad parameter.
class InvalidInputError : public Error {
 public:
  using Error::Error;
};

/// A file that cannot be read or written: missing, empty, truncated, malformed, unwritable.
class IoError : public Error {
 public:
  using Error::Error;
};

/// A model file that is missing, corrupt, or was written for another configuration or format.
class ModelError : public Error {
 public:
  using Error::Error;
};

/// Long work stopped because the user asked (Ctrl-C) or a time budget ran out.
class InterruptedError : public Error {
 public:
  using Error::Error;
};

}  // namespace paco
