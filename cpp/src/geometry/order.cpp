#include "hugger/geometry/order.hpp"

#include <array>
#include <cstdint>
#include <cstring>

namespace hugger {

namespace {

/// The bits of x (-0 taken as +0) as an unsigned integer in the same order as the doubles.
std::uint64_t order_key(double x) {
  x += 0.0;
  std::uint64_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  return bits >> 63 ? ~bits : bits | (std::uint64_t{1} << 63);
}

}  // namespace

std::vector<int> ascending_order(const std::vector<double>& values) {
  // A least-significant-digit radix sort of the keys' 11-bit digits, stable (so ties keep the
  // indices' order); digits that all keys share are skipped. Branch-free, where a comparison
  // sort of such values is a coin toss per comparison.
  constexpr int kBits = 11, kDigits = (64 + kBits - 1) / kBits, kBuckets = 1 << kBits;
  const int n = static_cast<int>(values.size());
  std::vector<std::uint64_t> key(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) key[i] = order_key(values[i]);
  std::vector<int> order(static_cast<std::size_t>(n)), scratch(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) order[i] = i;
  std::vector<std::array<int, kBuckets>> count(kDigits);
  for (auto& c : count) c.fill(0);
  for (const std::uint64_t k : key)
    for (int d = 0; d < kDigits; ++d) ++count[d][(k >> (kBits * d)) & (kBuckets - 1)];
  for (int d = 0; d < kDigits; ++d) {
    std::array<int, kBuckets>& c = count[d];
    if (n == 0 || c[(key[0] >> (kBits * d)) & (kBuckets - 1)] == n) continue;
    for (int b = 0, sum = 0; b < kBuckets; ++b) {
      const int here = c[b];
      c[b] = sum;
      sum += here;
    }
    for (const int i : order) scratch[c[(key[i] >> (kBits * d)) & (kBuckets - 1)]++] = i;
    order.swap(scratch);
  }
  return order;
}

}  // namespace hugger
