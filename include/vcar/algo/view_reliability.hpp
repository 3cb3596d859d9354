#pragma once
// Beyond the paper: how far each view's mask can be trusted, from how it agrees with the
// consensus of all views (docs/robust.md, Eq. R13).
//
// A segmenter fails per frame: a mask on the wrong object, a part of the target, a leak into the
// floor. Eq. 2 counts every view alike, so a frame that failed outvotes nothing on its own but
// pulls every ratio it touches. Eq. R13 weighs view j by the agreement of its mask with the
// consensus S (the candidates the round's vote keeps), measured on the candidates it sees:
//   A_j = |S ∩ F_j|,  B_j = |F_j \ S|,  C_j = |S ∩ V_j \ F_j|
//   r_j = A_j / (A_j + B_j + C_j)         (Eq. R13a: Jaccard of the mask and the consensus;
//                                          1 when the view sees neither)
//   V^r_i = sum_j r_j v_ij,  F^r_i = sum_j r_j f_ij                       (Eq. R13b)
// with V_j the candidates view j sees (v_ij = 1) and F_j those of them in its mask (f_ij = 1).
// A mask on another object has r_j = 0 and stops voting; one that covers half the target, or
// leaks as much again, votes with about half a view. The consensus is the unweighted vote at
// first and the weighted one after (RobustVoting::weigh_views iterates).
//
// Storage: two bits per candidate and view (V_j and F_j), n / 4 bytes per view.
#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace vcar {

class ViewReliability {
public:
  // n candidates.
  explicit ViewReliability(std::size_t n = 0) : n_(n), words_((n + 63) / 64) {}

  std::size_t views() const noexcept { return seen_.size(); }
  std::size_t size() const noexcept { return n_; }

  // Starts the record of the next view (every bit clear).
  void add_view() {
    seen_.emplace_back(words_, 0);
    fg_.emplace_back(words_, 0);
  }
  // Candidate k is seen by the latest view, in its mask when `in_mask`. Threads may call this for
  // candidates in different 64-candidate words at once (RobustVoting's chunks are multiples of 64).
  void see(std::size_t k, bool in_mask) {
    const std::uint64_t bit = std::uint64_t{1} << (k & 63);
    seen_.back()[k >> 6] |= bit;
    if (in_mask) fg_.back()[k >> 6] |= bit;
  }
  // see(k, in_mask) for every k in [k0, k1), k0 a multiple of 64 (a word at a time).
  void see_all(std::size_t k0, std::size_t k1, bool in_mask) {
    for (std::size_t k = k0; k < k1; k += 64) {
      const std::size_t count = std::min<std::size_t>(64, k1 - k);
      const std::uint64_t bits = count == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << count) - 1;
      seen_.back()[k >> 6] |= bits;
      if (in_mask) fg_.back()[k >> 6] |= bits;
    }
  }

  // Eq. R13a for every view, the consensus S as a bitset of n bits (ViewReliability::bits).
  std::vector<float> agreement(const std::vector<std::uint64_t>& consensus) const {
    std::vector<float> r(views(), 1.f);
    for (std::size_t j = 0; j < views(); ++j) {
      std::size_t a = 0, b = 0, c = 0;
      for (std::size_t w = 0; w < words_; ++w) {
        const std::uint64_t s = consensus[w] & seen_[j][w], f = fg_[j][w];
        a += static_cast<std::size_t>(std::popcount(s & f));
        b += static_cast<std::size_t>(std::popcount(f & ~s));
        c += static_cast<std::size_t>(std::popcount(s & ~f));
      }
      if (a + b + c > 0) r[j] = static_cast<float>(a) / static_cast<float>(a + b + c);  // Eq. R13a
    }
    return r;
  }

  // Eq. R13b: V^r and F^r of every candidate for the view weights r.
  void weighted(const std::vector<float>& r, std::vector<float>& V, std::vector<float>& F) const {
    V.assign(n_, 0.f);
    F.assign(n_, 0.f);
    for (std::size_t j = 0; j < views(); ++j) {
      if (r[j] == 0.f) continue;
      for (std::size_t w = 0; w < words_; ++w)
        for (std::uint64_t s = seen_[j][w]; s; s &= s - 1) {
          const std::size_t k = w * 64 + static_cast<std::size_t>(std::countr_zero(s));
          V[k] += r[j];                                                                       // Eq. R13b
          if (fg_[j][w] >> (k & 63) & 1) F[k] += r[j];
        }
    }
  }

  // A bitset of n bits with bit k set where keep(k).
  template <class Keep>
  std::vector<std::uint64_t> bits(Keep&& keep) const {
    std::vector<std::uint64_t> out(words_, 0);
    for (std::size_t k = 0; k < n_; ++k)
      if (keep(k)) out[k >> 6] |= std::uint64_t{1} << (k & 63);
    return out;
  }

private:
  std::size_t n_ = 0, words_ = 0;
  std::vector<std::vector<std::uint64_t>> seen_, fg_;  // V_j, F_j per view
};

}  // namespace vcar
