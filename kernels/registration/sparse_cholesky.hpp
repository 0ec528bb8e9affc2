#pragma once
//! Sparse Cholesky for the Gauss–Newton normal equations of the coarse alignment (§4.2): the symbolic
//! analysis is done once per sparsity pattern and reused by every numeric factorisation. Two backends:
//! Eigen's SimplicialLDLT and CHOLMOD's supernodal LLT (SuiteSparse); see bench/registration for the
//! measurement behind the default.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>

namespace topotrack {

enum class CholeskyBackend { EigenLDLT, Cholmod };

//! The default backend (the faster one as measured).
inline constexpr CholeskyBackend kDefaultCholeskyBackend = CholeskyBackend::Cholmod;

class SparseCholesky {
public:
  using Matrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

  explicit SparseCholesky(CholeskyBackend backend = kDefaultCholeskyBackend);
  ~SparseCholesky();
  SparseCholesky(SparseCholesky&&) noexcept;
  SparseCholesky& operator=(SparseCholesky&&) noexcept;

  CholeskyBackend backend() const { return backend_; }
  //! Symbolic analysis of the lower triangle of `lower` (only its pattern is read).
  void analyze(const Matrix& lower);
  //! Numeric factorisation of a matrix with the analysed pattern. \throw SolverError if not positive definite.
  void factorize(const Matrix& lower);
  //! x = A^{-1} b with the last factorisation. \throw SolverError when the solve fails.
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const;
  //! Several right-hand sides at once (the columns of b).
  Eigen::MatrixXd solve(const Eigen::MatrixXd& b) const;
  //! Entries of the factor L (diagonal included) of the last factorisation.
  std::size_t factor_nonzeros() const;

private:
  struct Impl;
  CholeskyBackend backend_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace topotrack
