// The argument checks: the macros' messages.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "hugger/check.hpp"
#include "hugger/hand/hand_model.hpp"

using namespace hugger;

namespace {

/// The message f throws as std::invalid_argument ("" when it does not throw).
template <class F>
std::string message_of(F&& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(Checks, MacrosThrowOneLineMessagesWithTheValues) {
  const double x = -0.5;
  EXPECT_EQ(message_of([&] { HUGGER_CHECK_ARGUMENT(x > 0.0, "x must be positive, got " << x); }),
            "x must be positive, got -0.5");
  EXPECT_EQ(message_of([&] { HUGGER_CHECK_ARGUMENT(x < 0.0, "never"); }), "");
  EXPECT_EQ(message_of([] { HUGGER_CHECK_ARGUMENT_SIZE(4, 6, "joints", "points"); }), "joints must hold 6 points, got 4");
  const MatrixX m(2, 3);
  EXPECT_EQ(message_of([&] { HUGGER_CHECK_ARGUMENT_SHAPE(m, 5, 3, "angles"); }),
            "angles must be a (5, 3) array, got (2, 3)");
  EXPECT_EQ(message_of([&] { HUGGER_CHECK_ARGUMENT_SHAPE(m, 2, 3, "angles"); }), "");
}

TEST(Checks, HandCountsAreBoundedByTheConstants) {
  EXPECT_NO_THROW(HandModel::uniform(kMaxFingers, 2, 0.02, 0.0, 0.03, 0.01));
  EXPECT_EQ(message_of([] { HandModel::uniform(kMaxFingers + 1, 2, 0.02, 0.0, 0.03, 0.01); }),
            "fingers must be between 1 and 64, got 65");
  EXPECT_EQ(message_of([] { HandModel::uniform(2, kMaxLinks + 1, 0.02, 0.0, 0.03, 0.01); }),
            "links must be between 1 and 256, got 257");
}
