#include "kernels/registration/sparse_cholesky.hpp"

#include <Eigen/CholmodSupport>
#include <Eigen/SparseCholesky>

#include "io/error.hpp"

namespace topotrack {

struct SparseCholesky::Impl {
  Eigen::SimplicialLDLT<Matrix, Eigen::Lower, Eigen::AMDOrdering<int>> ldlt;
  Eigen::CholmodSupernodalLLT<Matrix, Eigen::Lower> cholmod;
};

SparseCholesky::SparseCholesky(CholeskyBackend backend) : backend_(backend), impl_(std::make_unique<Impl>()) {}
SparseCholesky::~SparseCholesky() = default;
SparseCholesky::SparseCholesky(SparseCholesky&&) noexcept = default;
SparseCholesky& SparseCholesky::operator=(SparseCholesky&&) noexcept = default;

void SparseCholesky::analyze(const Matrix& lower) {
  if (backend_ == CholeskyBackend::Cholmod) impl_->cholmod.analyzePattern(lower);
  else impl_->ldlt.analyzePattern(lower);
}

void SparseCholesky::factorize(const Matrix& lower) {
  Eigen::ComputationInfo info;
  if (backend_ == CholeskyBackend::Cholmod) {
    impl_->cholmod.factorize(lower);
    info = impl_->cholmod.info();
  } else {
    impl_->ldlt.factorize(lower);
    info = impl_->ldlt.info();
  }
  if (info != Eigen::Success)
    TT_THROW(SolverError, "sparse Cholesky: factorisation of a " << lower.rows() << " x " << lower.cols()
                                                                 << " system failed (not positive definite)");
}

Eigen::VectorXd SparseCholesky::solve(const Eigen::VectorXd& b) const { return solve(Eigen::MatrixXd(b)).col(0); }

Eigen::MatrixXd SparseCholesky::solve(const Eigen::MatrixXd& b) const {
  Eigen::MatrixXd x;
  Eigen::ComputationInfo info;
  if (backend_ == CholeskyBackend::Cholmod) {
    x = impl_->cholmod.solve(b);
    info = impl_->cholmod.info();
  } else {
    x = impl_->ldlt.solve(b);
    info = impl_->ldlt.info();
  }
  if (info != Eigen::Success || !x.allFinite())
    TT_THROW(SolverError, "sparse Cholesky: solve of a " << b.rows() << " x " << b.cols() << " system failed");
  return x;
}

std::size_t SparseCholesky::factor_nonzeros() const {
  if (backend_ == CholeskyBackend::Cholmod) return std::size_t(impl_->cholmod.cholmod().lnz);
  return std::size_t(impl_->ldlt.matrixL().nestedExpression().nonZeros() + impl_->ldlt.rows());
}

}  // namespace topotrack
