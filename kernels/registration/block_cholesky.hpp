#pragma once
//! Sparse Cholesky L L^T of a symmetric positive definite matrix made of dense 4 x 4 blocks over a
//! graph: the per-coordinate preconditioner of the coarse alignment's Gauss–Newton systems (§4.2),
//! whose 4 unknowns per graph node are a column of A_j and b_j for one coordinate. Ordered by
//! approximate minimum degree on the node graph, then renumbered in elimination-tree postorder, so each
//! node's unknowns stay together, L is stored as 4 x 4 blocks (the triangular solves, one per PCG
//! iteration, serve the x, y and z right-hand sides at once) and every subtree is a contiguous range.
//! Factorisation (left-looking, by block columns) and solves run independent subtrees in parallel; each
//! entry is computed by the same operations in the same order whatever the schedule, so the result is
//! bit-identical for any thread count. The symbolic analysis is done once per graph and reused.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace topotrack {

class BlockCholesky {
public:
  using Matrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

  BlockCholesky();
  ~BlockCholesky();
  BlockCholesky(BlockCholesky&&) noexcept;
  BlockCholesky& operator=(BlockCholesky&&) noexcept;

  //! Ordering and symbolic analysis for the graph (CSR: neighbours of node j are
  //! neighbors[offset[j]] .. neighbors[offset[j + 1] - 1]); the matrix has 4 unknowns per node, node j
  //! owning rows 4 j .. 4 j + 3. \throw InvalidInput on a malformed graph.
  void analyze(const std::vector<std::uint32_t>& offset, const std::vector<std::uint32_t>& neighbors);
  //! Numeric factorisation of the lower triangle `lower` (4N x 4N, nonzeros within the graph's blocks).
  //! \throw SolverError if not positive definite, InvalidInput on a size mismatch.
  void factorize(const Matrix& lower);
  //! In place, three right-hand sides interleaved: x holds 4N rows of 3 values (row-major).
  //! \throw SolverError when the result is not finite.
  void solve3(double* x) const;
  //! Scalar entries of the block factor (diagonal blocks included), zeros inside blocks counted.
  std::size_t factor_nonzeros() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace topotrack
