/// @file sparse_lu.cpp
/// @brief bvp::SparseLu (sparse_lu.hpp) on KLU's 64-bit interface.
#include "tdcr/bvp/sparse_lu.hpp"

#include <klu.h>

#include <algorithm>
#include <type_traits>
#include <vector>

namespace tdcr::bvp {

static_assert(std::is_same<long, SuiteSparse_long>::value,
              "KLU's long index type (klu_l_*) must be long");

struct SparseLu::Impl {
  explicit Impl(double ratio) : growth_ratio(ratio) {
    klu_l_defaults(&common);
    // Fill-reducing ordering of each BTF block: AMD on A + A^T (KLU's default). It also gives
    // KLU a fill estimate to size the LU memory by; COLAMD (SUNLinSol_KLU's choice) does not, and
    // KLU then reserves 10 nnz(A), several times what the shooting Jacobians need.
    common.ordering = 0;
  }
  ~Impl() { release(); }
  void release_numeric() {
    if (numeric) klu_l_free_numeric(&numeric, &common);
  }
  void release() {
    release_numeric();
    if (symbolic) klu_l_free_symbolic(&symbolic, &common);
  }
  bool same_pattern(long n, const long* cp, const long* ri) const {
    return static_cast<long>(col_ptr.size()) == n + 1 && std::equal(col_ptr.begin(), col_ptr.end(), cp) &&
           std::equal(row_idx.begin(), row_idx.end(), ri);
  }

  klu_l_common common{};
  klu_l_symbolic* symbolic = nullptr;
  klu_l_numeric* numeric = nullptr;
  std::vector<long> col_ptr, row_idx;  // the analysed pattern
  std::vector<long> cp_buf, ri_buf;    // SparsityPattern converted to 64-bit indices
  double growth_ratio;             // kept refactorisations: rgrowth >= this x reference
  double reference_rgrowth = 0.0;  // of the last pivoting factorisation
  SparseLuStatistics stats;
};

SparseLu::SparseLu(double refactor_growth_ratio) : impl_(std::make_unique<Impl>(refactor_growth_ratio)) {}
SparseLu::~SparseLu() = default;
SparseLu::SparseLu(SparseLu&&) noexcept = default;
SparseLu& SparseLu::operator=(SparseLu&&) noexcept = default;

SparseLu::Status SparseLu::factorize(long n, const long* col_ptr, const long* row_idx, const double* values) {
  Impl& s = *impl_;
  if (n < 0) return Status::Failed;
  if (!s.symbolic || !s.same_pattern(n, col_ptr, row_idx)) {
    s.release();
    s.col_ptr.assign(col_ptr, col_ptr + n + 1);
    s.row_idx.assign(row_idx, row_idx + col_ptr[n]);
    s.symbolic = klu_l_analyze(n, s.col_ptr.data(), s.row_idx.data(), &s.common);
    if (!s.symbolic) {
      s.col_ptr.clear();
      return Status::Failed;
    }
    ++s.stats.symbolic_analyses;
  }
  // KLU's interface takes non-const arrays but does not write them.
  long* cp = s.col_ptr.data();
  long* ri = s.row_idx.data();
  double* v = const_cast<double*>(values);
  if (s.numeric) {
    if (klu_l_refactor(cp, ri, v, s.symbolic, s.numeric, &s.common) &&
        klu_l_rgrowth(cp, ri, v, s.symbolic, s.numeric, &s.common) &&
        s.common.rgrowth >= s.growth_ratio * s.reference_rgrowth) {
      ++s.stats.refactorizations;
      return Status::Success;
    }
    // Failed (e.g. a zero pivot in the reused order) or too much growth: pivot afresh.
    ++s.stats.rejected_refactorizations;
    s.release_numeric();
  }
  s.numeric = klu_l_factor(cp, ri, v, s.symbolic, &s.common);
  if (!s.numeric) return s.common.status == KLU_SINGULAR ? Status::Singular : Status::Failed;
  ++s.stats.factorizations;
  s.reference_rgrowth = klu_l_rgrowth(cp, ri, v, s.symbolic, s.numeric, &s.common) ? s.common.rgrowth : 0.0;
  return Status::Success;
}

SparseLu::Status SparseLu::factorize(const SparsityPattern& pattern, const double* values) {
  Impl& s = *impl_;
  if (pattern.rows != pattern.cols || static_cast<int>(pattern.col_ptr.size()) != pattern.cols + 1)
    return Status::Failed;
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
  if (!s.numeric) return false;
  return klu_l_solve(s.symbolic, s.numeric, s.symbolic->n, 1, b, &s.common) != 0;
}

bool SparseLu::factorized() const { return impl_->numeric != nullptr; }
const SparseLuStatistics& SparseLu::statistics() const { return impl_->stats; }
long SparseLu::integer_words() const { return static_cast<long>(impl_->col_ptr.size() + impl_->row_idx.size()); }
long SparseLu::real_words() const { return static_cast<long>(impl_->common.memusage / sizeof(double)); }

}  // namespace tdcr::bvp
