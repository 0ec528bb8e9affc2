#pragma once
//! Typed errors of topotrack. Library code throws, never exits or prints; the CLI maps each type
//! to an exit code (0 ok, 1 runtime error, 2 usage, 3 invalid input).
#include <sstream>
#include <stdexcept>
#include <string>

namespace topotrack {

//! Base of every topotrack error.
class Error : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};
//! The input data is malformed or violates a documented precondition (exit code 3).
class InvalidInput : public Error {
public:
  using Error::Error;
};
//! A file could not be opened, read, written or renamed (exit code 1).
class IoError : public Error {
public:
  using Error::Error;
};
//! A mesh lost a connectivity invariant (closed 2-manifold, handles in range) (exit code 1).
class TopologyError : public Error {
public:
  using Error::Error;
};
//! A numerical solve failed (factorisation not positive definite, no convergence) (exit code 1).
class SolverError : public Error {
public:
  using Error::Error;
};
//! The command line is wrong (exit code 2).
class UsageError : public Error {
public:
  using Error::Error;
};

enum ExitCode : int { kExitOk = 0, kExitRuntime = 1, kExitUsage = 2, kExitInvalidInput = 3 };

//! The exit code the CLI uses for an exception of this type.
inline int exit_code_for(const std::exception& e) {
  if (dynamic_cast<const InvalidInput*>(&e)) return kExitInvalidInput;
  if (dynamic_cast<const UsageError*>(&e)) return kExitUsage;
  return kExitRuntime;
}

}  // namespace topotrack

//! Throw `Type` with a message streamed from the arguments:
//! TT_THROW(IoError, path << ":" << line << ": bad face index " << i);
#define TT_THROW(Type, stream_expr)                                                                \
  do {                                                                                             \
    std::ostringstream tt_throw_os_;                                                               \
    tt_throw_os_ << stream_expr;                                                                   \
    throw Type(tt_throw_os_.str());                                                                \
  } while (0)
