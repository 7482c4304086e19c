/// \file check.hpp
/// Argument checks of the engine (in the manner of pinocchio's PINOCCHIO_CHECK_INPUT_ARGUMENT
/// and PINOCCHIO_CHECK_ARGUMENT_SIZE). Each throws std::invalid_argument with a one-line
/// message; the Python binding turns it into a ValueError. The message is a stream expression,
/// so numbers print as they do on a std::ostream (6 significant digits):
///
///     HUGGER_CHECK_ARGUMENT(step > 0.0, "step must be positive, got " << step);
///     HUGGER_CHECK_ARGUMENT_SHAPE(angles, fingers, links, "angles");
#pragma once

#include <sstream>
#include <stdexcept>

/// Throws std::invalid_argument(message) unless `condition` holds; `message` may chain `<<`.
#define HUGGER_CHECK_ARGUMENT(condition, message)                 \
  do {                                                            \
    if (!(condition)) {                                           \
      std::ostringstream hugger_check_message_;                   \
      hugger_check_message_ << message;                           \
      throw std::invalid_argument(hugger_check_message_.str());   \
    }                                                             \
  } while (false)

/// A count: "<name> must hold <expected> <what>, got <size>" unless size == expected.
#define HUGGER_CHECK_ARGUMENT_SIZE(size, expected, name, what)                                        \
  HUGGER_CHECK_ARGUMENT((size) == (expected),                                                          \
                        name << " must hold " << (expected) << " " << what << ", got " << (size))

/// A matrix's shape: "<name> must be a (r, c) array, got (rows, cols)" unless it is r x c.
#define HUGGER_CHECK_ARGUMENT_SHAPE(matrix, expected_rows, expected_cols, name)                        \
  HUGGER_CHECK_ARGUMENT((matrix).rows() == (expected_rows) && (matrix).cols() == (expected_cols),      \
                        name << " must be a (" << (expected_rows) << ", " << (expected_cols)            \
                             << ") array, got (" << (matrix).rows() << ", " << (matrix).cols() << ")")
