#include "hugger/geometry/order.hpp"

#include <algorithm>
#include <array>
#include <cstdint>

#include "hugger/geometry/next.hpp"

namespace hugger {

namespace {

/// The bits of x (-0 taken as +0) as an unsigned integer in the same order as the doubles.
std::uint64_t order_key(double x) {
  const std::uint64_t bits = bits_of(x + 0.0);
  return bits >> 63 ? ~bits : bits | (std::uint64_t{1} << 63);
}

/// 0 .. n - 1 in (key, index) order: a least-significant-digit radix sort of the keys' 11-bit
/// digits from digit `first` up, stable (so ties keep the indices' order); digits that all keys
/// share are skipped. The passes are branch-free, where a comparison sort of such keys is a coin
/// toss per comparison. With `first` > 0 the digits below are left out of the passes, and the
/// keys equal in the sorted digits (rare where those are most of a key's bits) are then put in
/// order by their whole keys: the same order, in fewer passes.
template <class Key>
std::vector<int> radix_order(const std::vector<Key>& key, int first = 0) {
  constexpr int kBits = 11, kDigits = (8 * static_cast<int>(sizeof(Key)) + kBits - 1) / kBits,
                kBuckets = 1 << kBits;
  static_assert(kBits * (kDigits - 1) < 8 * sizeof(Key), "the top digit's shift is below the key's width");
  first = std::clamp(first, 0, kDigits - 1);
  const int n = static_cast<int>(key.size());
  std::vector<int> order(static_cast<std::size_t>(n)), scratch(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) order[i] = i;
  std::array<std::array<int, kBuckets>, kDigits> count;
  for (int d = first; d < kDigits; ++d) count[d].fill(0);
  for (const Key k : key)
    for (int d = first; d < kDigits; ++d) ++count[d][(k >> (kBits * d)) & (kBuckets - 1)];
  for (int d = first; d < kDigits; ++d) {
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
  if (first == 0) return order;
  // Keys equal in the sorted digits hold their indices in increasing order (the passes are
  // stable), and a key greater in those digits is greater: an insertion sort by the whole key
  // that moves an index only past strictly greater keys keeps (key, index) order and moves
  // nothing across runs of equal sorted digits. Where an index would move far (a long run of keys
  // alike in their high bits, out of order in the low ones), that whole run is sorted instead.
  constexpr int kShort = 16;
  const int shift = kBits * first;
  for (int k = 1; k < n; ++k) {
    const int x = order[k];
    const Key kx = key[x];
    if (!(key[order[k - 1]] > kx)) continue;  // in order: nearly every key
    int m = k - 1;
    while (m > 0 && k - m < kShort && key[order[m - 1]] > kx) --m;
    if (m > 0 && key[order[m - 1]] > kx) {
      const Key high = kx >> shift;
      int lo = m, hi = k + 1;
      while (lo > 0 && key[order[lo - 1]] >> shift == high) --lo;
      while (hi < n && key[order[hi]] >> shift == high) ++hi;
      std::sort(order.begin() + lo, order.begin() + hi,
                [&](int a, int b) { return key[a] < key[b] || (key[a] == key[b] && a < b); });
      k = hi - 1;
      continue;
    }
    for (int j = k; j > m; --j) order[j] = order[j - 1];
    order[m] = x;
  }
  return order;
}

}  // namespace

std::vector<int> ascending_order(const std::vector<double>& values) {
  std::vector<std::uint64_t> key(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) key[i] = order_key(values[i]);
  // The high 31 bits (sign, exponent, 19 bits of mantissa) in three passes instead of six over
  // all 64: finite doubles that agree in those bits differ by less than 2^-19 of their magnitude,
  // so the runs left for the whole keys are usually short (a long one is sorted by itself).
  return radix_order(key, 3);
}

std::vector<int> ascending_order(const std::vector<std::uint32_t>& values) { return radix_order(values); }

}  // namespace hugger
