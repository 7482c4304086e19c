// Hug rule H5's opening search, coarse_to_fine: every pass/fail pattern of up to 12 candidates.
#include <gtest/gtest.h>

#include <vector>

#include "hugger/planner/planner.hpp"

using namespace hugger;

namespace {

struct Outcome {
  int found = -1;
  int slot = -1;                 ///< the candidate whose result the caller's slot holds
  std::vector<int> asked;        ///< candidates asked, in turn
  bool asked_twice = false;
  bool out_of_range = false;
};

Outcome search(int count, int stride, unsigned pattern) {
  Outcome o;
  int kept = -2;
  std::vector<char> seen(static_cast<std::size_t>(count > 0 ? count : 1), 0);
  auto passes = [&](int k) {
    if (k < 0 || k >= count) {
      o.out_of_range = true;
      return false;
    }
    o.asked_twice = o.asked_twice || seen[static_cast<std::size_t>(k)];
    seen[static_cast<std::size_t>(k)] = 1;
    o.asked.push_back(k);
    o.slot = k;
    return ((pattern >> k) & 1u) != 0;
  };
  o.found = coarse_to_fine(count, stride, passes, [&] { kept = o.slot; }, [&] { o.slot = kept; });
  return o;
}

bool asked_first(int k, int count, int stride) { return k % stride == 0 || k == count - 1; }

}  // namespace

TEST(CoarseToFine, EveryPatternOfUpTo12Candidates) {
  for (int stride = 1; stride <= 4; ++stride) {
    for (int count = 0; count <= 12; ++count) {
      for (unsigned pattern = 0; pattern < (1u << count); ++pattern) {
        SCOPED_TRACE(testing::Message() << "stride " << stride << " count " << count << " pattern " << pattern);
        const Outcome o = search(count, stride, pattern);
        ASSERT_FALSE(o.out_of_range);
        ASSERT_FALSE(o.asked_twice);
        int first = -1, runs = 0;
        bool run_asked_first = false;
        for (int k = 0; k < count; ++k) {
          const bool p = (pattern >> k) & 1u;
          if (p && first < 0) first = k;
          if (p && (k == 0 || !((pattern >> (k - 1)) & 1u))) ++runs;
          if (p && asked_first(k, count, stride)) run_asked_first = true;
        }
        if (o.found >= 0) {
          // A candidate that passes, whose result the slot holds.
          EXPECT_TRUE((pattern >> o.found) & 1u);
          EXPECT_EQ(o.slot, o.found);
        } else {
          // None found: no candidate asked first passes.
          for (int k = 0; k < count; ++k)
            if (asked_first(k, count, stride)) EXPECT_FALSE((pattern >> k) & 1u) << k;
        }
        // One run holding a candidate asked first: its first candidate, as asking in turn finds.
        if (runs == 1 && run_asked_first) EXPECT_EQ(o.found, first);
        if (stride == 1) EXPECT_EQ(o.found, first);
        // At most the coarse candidates and the stride - 1 before the first that passes.
        const int coarse = count == 0 ? 0 : (count - 1) / stride + 1 + ((count - 1) % stride != 0);
        EXPECT_LE(static_cast<int>(o.asked.size()), coarse + stride - 1);
      }
    }
  }
}

TEST(CoarseToFine, NoCandidateOrAnyStride) {
  int asked = 0;
  auto passes = [&](int) {
    ++asked;
    return true;
  };
  auto none = [] {};
  EXPECT_EQ(coarse_to_fine(0, 3, passes, none, none), -1);
  EXPECT_EQ(asked, 0);
  EXPECT_EQ(coarse_to_fine(5, 2147483647, passes, none, none), 0);  // no overflow past the last
  auto fails = [&](int) {
    ++asked;
    return false;
  };
  asked = 0;
  EXPECT_EQ(coarse_to_fine(5, 2147483647, fails, none, none), -1);
  EXPECT_EQ(asked, 2);  // the first and the last
}
