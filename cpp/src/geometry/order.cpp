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

/// 0 .. n - 1 in (key, index) order: a least-significant-digit radix sort of the keys' 11-bit
/// digits, stable (so ties keep the indices' order); digits that all keys share are skipped.
/// Branch-free, where a comparison sort of such keys is a coin toss per comparison.
template <class Key>
std::vector<int> radix_order(const std::vector<Key>& key) {
  constexpr int kBits = 11, kDigits = (8 * static_cast<int>(sizeof(Key)) + kBits - 1) / kBits,
                kBuckets = 1 << kBits;
  const int n = static_cast<int>(key.size());
  std::vector<int> order(static_cast<std::size_t>(n)), scratch(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) order[i] = i;
  std::array<std::array<int, kBuckets>, kDigits> count{};
  for (const Key k : key)
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

}  // namespace

std::vector<int> ascending_order(const std::vector<double>& values) {
  std::vector<std::uint64_t> key(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) key[i] = order_key(values[i]);
  return radix_order(key);
}

std::vector<int> ascending_order(const std::vector<std::uint32_t>& values) { return radix_order(values); }

}  // namespace hugger
