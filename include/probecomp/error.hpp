#pragma once
// What probecomp throws when it cannot return a sound result. Every message is one line in the field's words
// that names the file (and line), the face or the cause: never a command-line option, so that the library,
// the command line and the Python bindings can all show it as it is.
//   InputError         points or options the method cannot use (a point file's bad line, no points, a
//                      non-positive probe radius, points nowhere near the model)
//   CadError           a CAD file that cannot be read or used as a model
//   RegistrationError  the points could not be registered to the model credibly
//   FitError           a surface that could not be fitted or offset where the caller needs one
// Where the caller can act on it, an error carries a Hint, which the command line and the Python package put in their
// own words (an option there, a keyword argument here) after the message.

#include <cstring>
#include <stdexcept>
#include <string>

namespace probecomp {

// What the caller can do about an error, beyond what its message says.
enum class Hint {
  None,
  // Give the registration a rough start (a 4 x 4 rigid transform, CAD -> machine), or check the CAD file, the frame
  // and the probe radius.
  InitialTransform,
  // That, or, when the part may really deviate from its model by about the probe radius, accept the doubtful
  // registration (RegisterOptions::accept_doubtful): the run then goes on with a warning.
  InitialTransformOrAcceptDoubtful,
  // The unit the caller declared for a point file disagrees with the file's own statement of it.
  DeclaredUnit,
};

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what, Hint hint = Hint::None) : std::runtime_error(what), hint_(hint) {}
  [[nodiscard]] Hint hint() const { return hint_; }

 private:
  Hint hint_;
};

class InputError : public Error {
 public:
  using Error::Error;
};

class CadError : public Error {
 public:
  using Error::Error;
};

class RegistrationError : public Error {
 public:
  using Error::Error;
};

class FitError : public Error {
 public:
  using Error::Error;
};

// The system's reason for a failed open(2) or write(2), errno as it left it, for the end of a message: " (No space
// left on device)", or nothing when errno is 0 (a failure that set none).
[[nodiscard]] inline std::string system_reason(int errno_value) {
  return errno_value != 0 ? " (" + std::string(std::strerror(errno_value)) + ")" : std::string();
}

}  // namespace probecomp
