// Error types: every failure the user can cause ends up as one of these, with a message
// that says what to change.
#pragma once
#include <stdexcept>
#include <string>

namespace granular {

// Bad input: a scene key that is missing, unknown or out of range.
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A run that became physically unsafe (time step too large, NaN, runaway overlap/energy).
struct PhysicsError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace granular
