#include "hooke/forces/element_force.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "hooke/parallel/loops.hpp"

namespace hooke {

ElementTerms::ElementTerms(std::shared_ptr<const ElementSet> set, int matrices)
    : m_set(std::move(set)), m_matrices(matrices) {
  HOOKE_ASSERT(m_set, "an element force needs an element set");
  m_k = m_set->stencil_size();
  HOOKE_ASSERT(m_k >= 1 && m_k <= kMaxStencil,
               m_set->name() << ": stencil size " << m_k << " outside 1.." << kMaxStencil);
}

template <class Evaluate, class Scatter>
bool ElementTerms::in_chunks(Evaluate&& evaluate, Scatter&& scatter) const {
  const size_t n = m_set->size();
  if (!run_parallel(static_cast<long long>(n), kParallelElements) || m_chunk_H.empty())
    return false;
  std::unique_lock<std::mutex> lock(m_chunk_mutex, std::try_to_lock);
  if (!lock.owns_lock()) return false;
  for (size_t c0 = 0; c0 < n; c0 += kChunk) {
    const size_t c1 = std::min(n, c0 + kChunk);
    const long long batches = static_cast<long long>((c1 - c0 + kBatch - 1) / kBatch);
#pragma omp parallel for schedule(dynamic, 4)
    for (long long b = 0; b < batches; ++b) {
      const size_t e0 = c0 + size_t(b) * kBatch;
      evaluate(e0, std::min(c1, e0 + kBatch), c0);
    }
    scatter(c0, c1);
  }
  return true;
}

void ElementTerms::scatter_vectors(size_t begin, size_t end, const double* g, double scale,
                                   VecRef f) const {
  const size_t dofs = size_t(3 * m_k);
  for (size_t e = begin; e < end; ++e) {
    const int* s = m_set->stencil(e);
    const double* ge = g + dofs * (e - begin);
    for (int a = 0; a < m_k; ++a)
      for (int c = 0; c < 3; ++c) f[3 * s[a] + c] += scale * ge[3 * a + c];
  }
}

void ElementTerms::scatter_blocks(size_t begin, size_t end, const double* B, double scale,
                                  SparseMatrix& A) const {
  const size_t dofs = size_t(3 * m_k), kk = size_t(m_k * m_k);
  double* values = A.valuePtr();
  for (size_t e = begin; e < end; ++e) {
    const double* Be = B + dofs * dofs * (e - begin);
    for (int a = 0; a < m_k; ++a)
      for (int c = 0; c < m_k; ++c) {
        const BlockSlot& slot = m_slots[e * kk + size_t(a * m_k + c)];
        double* p = values + slot.offset;
        // Block (a, c): rows 3a.., columns 3c.. of the column-major 3K x 3K matrix.
        for (int cc = 0; cc < 3; ++cc)
          for (int r = 0; r < 3; ++r)
            p[cc * slot.stride + r] += scale * Be[size_t(3 * c + cc) * dofs + size_t(3 * a + r)];
      }
  }
}

void ElementTerms::declare_blocks(BlockPattern& pattern) const {
  for (size_t e = 0; e < m_set->size(); ++e) {
    const int* s = m_set->stencil(e);
    for (int a = 0; a < m_k; ++a)
      for (int b = a + 1; b < m_k; ++b) pattern.add_pair(s[a], s[b]);
  }
}

void ElementTerms::bind(const BlockPattern& pattern) {
  const size_t n = m_set->size(), kk = size_t(m_k * m_k), dofs = size_t(3 * m_k);
  m_slots.resize(n * kk);
  for (size_t e = 0; e < n; ++e) {
    const int* s = m_set->stencil(e);
    for (int a = 0; a < m_k; ++a)
      for (int b = 0; b < m_k; ++b)
        m_slots[e * kk + size_t(a * m_k + b)] = pattern.slot(s[a], s[b]);
  }
  if (static_cast<long long>(n) >= kParallelElements) {
    m_chunk_g.assign(kChunk * dofs, 0.0);
    m_chunk_H.assign(kChunk * dofs * dofs * size_t(m_matrices), 0.0);
  }
}

void ElementTerms::check_bound() const {
  HOOKE_ASSERT(m_slots.size() == m_set->size() * size_t(m_k * m_k),
               m_set->name() << ": add_jacobians before bind");
}

// ---------------------------------------------------------------------------------------------

ElementForce::ElementForce(std::unique_ptr<ElementSet> set) : ElementTerms(std::move(set), 1) {}

std::unique_ptr<Force> ElementForce::localize(const LocalIndex& index) const {
  std::unique_ptr<ElementSet> set = m_set->localize(index);
  if (!set) return nullptr;
  return std::make_unique<ElementForce>(std::move(set));
}

void ElementForce::add_forces(ConstRef x, ConstRef /*v*/, VecRef f) const {
  const size_t n = m_set->size(), dofs = size_t(3 * m_k);
  if (in_chunks(
          [&](size_t e0, size_t e1, size_t c0) {
            m_set->gradient_hessian(x, e0, e1, PsdProjection::None,
                                    m_chunk_g.data() + dofs * (e0 - c0), nullptr);
          },
          [&](size_t c0, size_t c1) { scatter_vectors(c0, c1, m_chunk_g.data(), -1.0, f); }))
    return;
  std::array<double, kBatch * kMaxElementDofs> g;
  for (size_t b = 0; b < n; b += kBatch) {
    const size_t e_end = std::min(n, b + kBatch);
    m_set->gradient_hessian(x, b, e_end, PsdProjection::None, g.data(), nullptr);
    scatter_vectors(b, e_end, g.data(), -1.0, f);
  }
}

void ElementForce::add_discrete_gradient(ConstRef x0, ConstRef x1, ConstRef xm, ConstRef /*vm*/,
                                         VecRef f) const {
  const size_t n = m_set->size();
  std::array<double, kMaxElementDofs> g, d;
  for (size_t e = 0; e < n; ++e) {
    const int* s = m_set->stencil(e);
    m_set->gradient_hessian(xm, e, e + 1, PsdProjection::None, g.data(), nullptr);
    double dd = 0.0, gd = 0.0;
    for (int a = 0; a < m_k; ++a)
      for (int c = 0; c < 3; ++c) {
        const int i = 3 * a + c;
        d[size_t(i)] = x1[3 * s[a] + c] - x0[3 * s[a] + c];
        dd += d[size_t(i)] * d[size_t(i)];
        gd += g[size_t(i)] * d[size_t(i)];
      }
    double w = 0.0;  // the correction's weight along d
    if (dd > 0.0) w = (m_set->energy(x1, e, e + 1) - m_set->energy(x0, e, e + 1) - gd) / dd;
    for (int a = 0; a < m_k; ++a)
      for (int c = 0; c < 3; ++c) {
        const int i = 3 * a + c;
        f[3 * s[a] + c] -= g[size_t(i)] + w * d[size_t(i)];
      }
  }
}

double ElementForce::potential_energy(ConstRef x) const {
  return m_set->energy(x, 0, m_set->size());
}

void ElementForce::add_jacobians(ConstRef x, ConstRef /*v*/, const JacobianOptions& options,
                                 SparseMatrix& K, SparseMatrix& /*D*/) const {
  check_bound();
  const size_t n = m_set->size(), dofs = size_t(3 * m_k);
  const PsdProjection projection =
      options.clamp_compressed ? PsdProjection::Clamp : PsdProjection::None;
  if (in_chunks(
          [&](size_t e0, size_t e1, size_t c0) {
            m_set->gradient_hessian(x, e0, e1, projection, m_chunk_g.data() + dofs * (e0 - c0),
                                    m_chunk_H.data() + dofs * dofs * (e0 - c0));
          },
          [&](size_t c0, size_t c1) { scatter_blocks(c0, c1, m_chunk_H.data(), -1.0, K); }))
    return;
  std::array<double, kBatch * kMaxElementDofs> g;
  std::array<double, kBatch * kMaxElementDofs * kMaxElementDofs> H;
  for (size_t b = 0; b < n; b += kBatch) {
    const size_t e_end = std::min(n, b + kBatch);
    m_set->gradient_hessian(x, b, e_end, projection, g.data(), H.data());
    scatter_blocks(b, e_end, H.data(), -1.0, K);
  }
}

// ---------------------------------------------------------------------------------------------

ElementDamping::ElementDamping(std::shared_ptr<const ElementSet> set, double beta)
    : ElementTerms(std::move(set), 2), m_beta(beta) {
  HOOKE_ASSERT(m_set->has_damping(), m_set->name() << " has no damping form");
  HOOKE_ASSERT(m_beta > 0.0 && std::isfinite(m_beta),
               m_set->name() << ": damping " << m_beta << " must be finite and > 0");
  m_name = std::string(m_set->name()) + "-damping";
}

std::unique_ptr<Force> ElementDamping::localize(const LocalIndex& index) const {
  std::unique_ptr<ElementSet> set = m_set->localize(index);
  if (!set) return nullptr;
  return std::make_unique<ElementDamping>(std::move(set), m_beta);
}

void ElementDamping::add_forces(ConstRef x, ConstRef v, VecRef f) const {
  const size_t n = m_set->size(), dofs = size_t(3 * m_k);
  if (in_chunks(
          [&](size_t e0, size_t e1, size_t c0) {
            m_set->damping(x, v, e0, e1, m_chunk_g.data() + dofs * (e0 - c0), nullptr, nullptr);
          },
          [&](size_t c0, size_t c1) { scatter_vectors(c0, c1, m_chunk_g.data(), m_beta, f); }))
    return;
  std::array<double, kBatch * kMaxElementDofs> g;
  for (size_t b = 0; b < n; b += kBatch) {
    const size_t e_end = std::min(n, b + kBatch);
    m_set->damping(x, v, b, e_end, g.data(), nullptr, nullptr);
    scatter_vectors(b, e_end, g.data(), m_beta, f);
  }
}

void ElementDamping::add_jacobians(ConstRef x, ConstRef v, const JacobianOptions& options,
                                   SparseMatrix& K, SparseMatrix& D) const {
  check_bound();
  HOOKE_ASSERT(D.nonZeros() == K.nonZeros(), m_name << ": add_jacobians needs the system's D");
  const size_t n = m_set->size(), dofs = size_t(3 * m_k), block = dofs * dofs;
  const bool position = options.damping_position_terms;
  // The velocity Jacobians of a chunk, then (position) its position Jacobians, in one buffer.
  if (in_chunks(
          [&](size_t e0, size_t e1, size_t c0) {
            m_set->damping(x, v, e0, e1, m_chunk_g.data() + dofs * (e0 - c0),
                           m_chunk_H.data() + block * (e0 - c0),
                           position ? m_chunk_H.data() + block * (kChunk + e0 - c0) : nullptr);
          },
          [&](size_t c0, size_t c1) {
            scatter_blocks(c0, c1, m_chunk_H.data(), m_beta, D);
            if (position) scatter_blocks(c0, c1, m_chunk_H.data() + block * kChunk, m_beta, K);
          }))
    return;
  // Serially one element at a time, to keep the two blocks' scratch on the stack small.
  std::array<double, kMaxElementDofs> g;
  std::array<double, kMaxElementDofs * kMaxElementDofs> Dv, Dx;
  for (size_t e = 0; e < n; ++e) {
    m_set->damping(x, v, e, e + 1, g.data(), Dv.data(), position ? Dx.data() : nullptr);
    scatter_blocks(e, e + 1, Dv.data(), m_beta, D);
    if (position) scatter_blocks(e, e + 1, Dx.data(), m_beta, K);
  }
}

}  // namespace hooke
