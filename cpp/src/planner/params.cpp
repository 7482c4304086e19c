// The planner's argument rules that need no hand or skin: the parameters' ranges and the timeout.
#include <cmath>

#include "hugger/check.hpp"
#include "hugger/planner/planner.hpp"

namespace hugger {

namespace {
void check_length(double value, const char* name) {
  HUGGER_CHECK_ARGUMENT(std::isnan(value) || (std::isfinite(value) && value > 0.0),
                        name << " must be a positive finite number, got " << value);
}
}  // namespace

void check_params(const PlannerParams& params) {
  check_length(params.step, "step");
  check_length(params.epsilon, "epsilon");
  check_length(params.contact_tolerance, "contact_tolerance");
  HUGGER_CHECK_ARGUMENT(params.max_iterations >= 1 && params.max_iterations <= kMaxIterations,
                        "max_iterations must be between 1 and " << kMaxIterations << ", got " << params.max_iterations);
}

double check_timeout(double seconds) {
  HUGGER_CHECK_ARGUMENT(std::isfinite(seconds) && seconds > 0.0,
                        "timeout must be a positive finite number of seconds, got " << seconds);
  return seconds;
}

}  // namespace hugger
