// Typed exceptions for bad user input (unknown model, invalid option, unwritable file, ...).
// Numerical trouble inside the time loop does not throw: it returns a Status (status.hpp).
// Messages name the value or symbol at fault and say what to do about it.
#pragma once

#include <stdexcept>
#include <string>

namespace nhdyn {

// Base of every error nhdyn reports to a user.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

// A value given by the user is out of range or inconsistent (a tolerance, a time, a name).
class InputError : public Error {
 public:
  using Error::Error;
};

// A file cannot be read or written.
class FileError : public Error {
 public:
  using Error::Error;
};

// A model is ill-posed at the state it is evaluated (dependent constraints, inertia matrix not
// positive definite, non-finite terms); thrown by the checks run before a simulation starts.
class ModelError : public Error {
 public:
  using Error::Error;
};

// A simulation stopped on numerical trouble; the message says where (t) and what.
class SimulationError : public Error {
 public:
  using Error::Error;
};

}  // namespace nhdyn
