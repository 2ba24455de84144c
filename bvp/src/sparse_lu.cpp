/// @file sparse_lu.cpp
/// @brief bvp::SparseLu (sparse_lu.hpp) on KLU's 64-bit interface.
#include "tdcr/bvp/sparse_lu.hpp"

#include <klu.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <type_traits>
#include <vector>

namespace tdcr::bvp {

static_assert(std::is_same<long, SuiteSparse_long>::value,
              "KLU's long index type (klu_l_*) must be long");

namespace {

// One analysed pattern: KLU's symbolic analysis, the last numeric factorisation on it and the
// reciprocal pivot growth of the pivoting factorisation whose order refactorisations reuse.
struct Slot {
  klu_l_symbolic* symbolic = nullptr;
  klu_l_numeric* numeric = nullptr;
  std::vector<long> col_ptr, row_idx;  // the analysed pattern (empty: slot unused)
  double reference_rgrowth = 0.0;
  long last_use = 0;

  void release_numeric(klu_l_common& c) {
    if (numeric) klu_l_free_numeric(&numeric, &c);
  }
  void release(klu_l_common& c) {
    release_numeric(c);
    if (symbolic) klu_l_free_symbolic(&symbolic, &c);
    col_ptr.clear();
    row_idx.clear();
  }
  bool holds(long n, const long* cp, const long* ri) const {
    return symbolic && static_cast<long>(col_ptr.size()) == n + 1 && std::equal(col_ptr.begin(), col_ptr.end(), cp) &&
           std::equal(row_idx.begin(), row_idx.end(), ri);
  }
};

// Parity of a permutation: a cycle of length L is L - 1 transpositions.
int permutation_sign(const long* perm, long n, std::vector<char>& visited) {
  visited.assign(static_cast<size_t>(n), 0);
  int sign = 1;
  for (long i = 0; i < n; ++i) {
    if (visited[i]) continue;
    for (long k = perm[i]; k != i; k = perm[k]) {
      visited[k] = 1;
      sign = -sign;
    }
    visited[i] = 1;
  }
  return sign;
}

}  // namespace

struct SparseLu::Impl {
  explicit Impl(double ratio) : growth_ratio(ratio) {
    klu_l_defaults(&common);
    // Fill-reducing ordering of each BTF block: AMD on A + A^T (KLU's default). It also gives
    // KLU a fill estimate to size the LU memory by; COLAMD (SUNLinSol_KLU's choice) does not, and
    // KLU then reserves 10 nnz(A), several times what the shooting Jacobians need.
    common.ordering = 0;
  }
  ~Impl() {
    for (Slot& s : slots) s.release(common);
  }

  // The slot analysed for this pattern, or the least recently used one, analysed afresh.
  Slot* slot_for(long n, const long* cp, const long* ri) {
    ++clock;
    for (Slot& s : slots)
      if (s.holds(n, cp, ri)) {
        s.last_use = clock;
        return &s;
      }
    Slot& s = *std::min_element(slots.begin(), slots.end(),
                                [](const Slot& a, const Slot& b) { return a.last_use < b.last_use; });
    s.release(common);
    s.col_ptr.assign(cp, cp + n + 1);
    s.row_idx.assign(ri, ri + cp[n]);
    s.symbolic = klu_l_analyze(n, s.col_ptr.data(), s.row_idx.data(), &common);
    if (!s.symbolic) {
      s.release(common);
      return nullptr;
    }
    s.last_use = clock;
    ++stats.symbolic_analyses;
    return &s;
  }

  klu_l_common common{};
  std::array<Slot, SparseLu::kPatternSlots> slots;
  Slot* current = nullptr;             // the slot of the last successful factorisation
  long clock = 0;
  std::vector<long> cp_buf, ri_buf;    // SparsityPattern converted to 64-bit indices
  std::vector<char> visited;           // permutation parity in determinant()
  double growth_ratio;                 // kept refactorisations: rgrowth >= this x reference
  SparseLuStatistics stats;
};

SparseLu::SparseLu(double refactor_growth_ratio) : impl_(std::make_unique<Impl>(refactor_growth_ratio)) {}
SparseLu::~SparseLu() = default;
SparseLu::SparseLu(SparseLu&&) noexcept = default;
SparseLu& SparseLu::operator=(SparseLu&&) noexcept = default;

SparseLu::Status SparseLu::factorize(long n, const long* col_ptr, const long* row_idx, const double* values) {
  Impl& s = *impl_;
  s.current = nullptr;
  if (n < 0) return Status::Failed;
  Slot* slot = s.slot_for(n, col_ptr, row_idx);
  if (!slot) return Status::Failed;
  // KLU's interface takes non-const arrays but does not write them.
  long* cp = slot->col_ptr.data();
  long* ri = slot->row_idx.data();
  double* v = const_cast<double*>(values);
  if (slot->numeric) {
    if (klu_l_refactor(cp, ri, v, slot->symbolic, slot->numeric, &s.common) &&
        klu_l_rgrowth(cp, ri, v, slot->symbolic, slot->numeric, &s.common) &&
        s.common.rgrowth >= s.growth_ratio * slot->reference_rgrowth) {
      ++s.stats.refactorizations;
      s.current = slot;
      return Status::Success;
    }
    // Failed (e.g. a zero pivot in the reused order) or too much growth: pivot afresh.
    ++s.stats.rejected_refactorizations;
    slot->release_numeric(s.common);
  }
  slot->numeric = klu_l_factor(cp, ri, v, slot->symbolic, &s.common);
  if (!slot->numeric) return s.common.status == KLU_SINGULAR ? Status::Singular : Status::Failed;
  ++s.stats.factorizations;
  slot->reference_rgrowth =
      klu_l_rgrowth(cp, ri, v, slot->symbolic, slot->numeric, &s.common) ? s.common.rgrowth : 0.0;
  s.current = slot;
  return Status::Success;
}

SparseLu::Status SparseLu::factorize(const SparsityPattern& pattern, const double* values) {
  Impl& s = *impl_;
  if (pattern.rows != pattern.cols || static_cast<int>(pattern.col_ptr.size()) != pattern.cols + 1) {
    s.current = nullptr;
    return Status::Failed;
  }
  // Convert the indices once per pattern object and contents (compared as the analysed ones).
  if (s.cp_buf.size() != pattern.col_ptr.size() || s.ri_buf.size() != pattern.row_idx.size() ||
      !std::equal(pattern.col_ptr.begin(), pattern.col_ptr.end(), s.cp_buf.begin()) ||
      !std::equal(pattern.row_idx.begin(), pattern.row_idx.end(), s.ri_buf.begin())) {
    s.cp_buf.assign(pattern.col_ptr.begin(), pattern.col_ptr.end());
    s.ri_buf.assign(pattern.row_idx.begin(), pattern.row_idx.end());
  }
  return factorize(pattern.cols, s.cp_buf.data(), s.ri_buf.data(), values);
}

bool SparseLu::solve(double* b) {
  Impl& s = *impl_;
  if (!s.current) return false;
  return klu_l_solve(s.current->symbolic, s.current->numeric, s.current->symbolic->n, 1, b, &s.common) != 0;
}

bool SparseLu::determinant(int& sign, double& log_abs) {
  Impl& s = *impl_;
  if (!s.current) return false;
  const klu_l_symbolic& sym = *s.current->symbolic;
  const klu_l_numeric& num = *s.current->numeric;
  const long n = sym.n;
  // Pnum: the final row order (BTF and partial pivoting), Q: the column order.
  sign = permutation_sign(num.Pnum, n, s.visited) * permutation_sign(sym.Q, n, s.visited);
  log_abs = 0.0;
  const double* u = static_cast<const double*>(num.Udiag);
  for (long k = 0; k < n; ++k) {
    if (u[k] < 0.0) sign = -sign;
    if (u[k] == 0.0) sign = 0;
    log_abs += std::log(std::abs(u[k]));
  }
  if (num.Rs)
    for (long k = 0; k < n; ++k) log_abs += std::log(num.Rs[k]);
  return true;
}

bool SparseLu::factorized() const { return impl_->current != nullptr; }
const SparseLuStatistics& SparseLu::statistics() const { return impl_->stats; }
long SparseLu::integer_words() const {
  long words = 0;
  for (const Slot& s : impl_->slots) words += static_cast<long>(s.col_ptr.size() + s.row_idx.size());
  return words;
}
long SparseLu::real_words() const { return static_cast<long>(impl_->common.memusage / sizeof(double)); }

}  // namespace tdcr::bvp
