// Block Cholesky of the coarse alignment's per-coordinate preconditioner (§4.2): solves agree with a
// dense solve, 1 and 2 threads agree bit for bit, bad input throws.
#include <gtest/gtest.h>

#include <tbb/task_arena.h>

#include <Eigen/Dense>
#include <cstring>
#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "io/error.hpp"
#include "kernels/registration/block_cholesky.hpp"

namespace topotrack {
namespace {

BlockCholesky::Matrix lower_of(const Eigen::MatrixXd& A) {
  return BlockCholesky::Matrix(A.triangularView<Eigen::Lower>().toDenseMatrix().sparseView());
}

struct Graph {
  std::vector<std::uint32_t> offset, neighbors;
};

// A w x h grid of nodes with 4-neighbours and one diagonal, sorted neighbour lists.
Graph grid(int w, int h) {
  std::vector<std::vector<std::uint32_t>> adj(std::size_t(w * h));
  auto link = [&](int a, int b) {
    adj[std::size_t(a)].push_back(std::uint32_t(b));
    adj[std::size_t(b)].push_back(std::uint32_t(a));
  };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (x + 1 < w) link(y * w + x, y * w + x + 1);
      if (y + 1 < h) link(y * w + x, (y + 1) * w + x);
      if (x + 1 < w && y + 1 < h) link(y * w + x, (y + 1) * w + x + 1);
    }
  Graph g;
  g.offset.push_back(0);
  for (auto& a : adj) {
    std::sort(a.begin(), a.end());
    g.neighbors.insert(g.neighbors.end(), a.begin(), a.end());
    g.offset.push_back(std::uint32_t(g.neighbors.size()));
  }
  return g;
}

// A random symmetric positive definite matrix with the graph's 4 x 4 block pattern (dense).
Eigen::MatrixXd random_spd(const Graph& g, std::uint32_t seed) {
  const int N = int(g.offset.size() - 1);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(4 * N, 4 * N);
  for (int j = 0; j < N; ++j)
    for (std::uint32_t q = g.offset[std::size_t(j)]; q < g.offset[std::size_t(j) + 1]; ++q) {
      const int k = int(g.neighbors[q]);
      if (k < j) continue;
      const Eigen::Matrix4d B = Eigen::Matrix4d::NullaryExpr([&] { return u(rng); });
      A.block<4, 4>(4 * k, 4 * j) = B;
      A.block<4, 4>(4 * j, 4 * k) = B.transpose();
    }
  // Diagonally dominant: positive definite.
  for (int i = 0; i < 4 * N; ++i) A(i, i) = A.row(i).cwiseAbs().sum() + 1 + u(rng);
  for (int j = 0; j < N; ++j) {
    const Eigen::Matrix4d B = Eigen::Matrix4d::NullaryExpr([&] { return 0.1 * u(rng); });
    A.block<4, 4>(4 * j, 4 * j) += B + B.transpose();
  }
  return A;
}

TEST(BlockCholesky, SolvesAgreeWithDense) {
  const Graph g = grid(9, 7);
  const Eigen::MatrixXd A = random_spd(g, 7);
  const BlockCholesky::Matrix lower = lower_of(A);
  BlockCholesky chol;
  chol.analyze(g.offset, g.neighbors);
  chol.factorize(lower);
  EXPECT_GE(chol.factor_nonzeros(), std::size_t(10 * 63));
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(A.rows(), 3);
  const Eigen::MatrixXd expected = A.ldlt().solve(B);
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> x = B;
  chol.solve3(x.data());
  EXPECT_LT((x - expected).cwiseAbs().maxCoeff(), 1e-10 * expected.cwiseAbs().maxCoeff());
  // A second factorisation with the same analysis.
  const Eigen::MatrixXd A2 = random_spd(g, 8);
  chol.factorize(lower_of(A2));
  x = B;
  chol.solve3(x.data());
  const Eigen::MatrixXd expected2 = A2.ldlt().solve(B);
  EXPECT_LT((x - expected2).cwiseAbs().maxCoeff(), 1e-10 * expected2.cwiseAbs().maxCoeff());
}

// Two grids side by side without a link (a forest), large enough for the subtrees to be solved in parallel.
TEST(BlockCholesky, ParallelSubtreesMatchOneThreadBitForBit) {
  Graph g = grid(40, 30);
  const Graph h = grid(25, 20);
  const std::uint32_t shift = std::uint32_t(g.offset.size() - 1);
  for (std::size_t j = 1; j < h.offset.size(); ++j) {
    for (std::uint32_t q = h.offset[j - 1]; q < h.offset[j]; ++q) g.neighbors.push_back(h.neighbors[q] + shift);
    g.offset.push_back(std::uint32_t(g.neighbors.size()));
  }
  const int N = int(g.offset.size() - 1);
  // Sparse assembly (a dense 7000^2 matrix would be too large): a block Laplacian plus a shift.
  std::vector<Eigen::Triplet<double, int>> t;
  for (int j = 0; j < N; ++j) {
    const double deg = double(g.offset[std::size_t(j) + 1] - g.offset[std::size_t(j)]);
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c <= r; ++c) t.emplace_back(4 * j + r, 4 * j + c, r == c ? deg + 0.5 + 0.1 * r : 0.05 * (r + c));
    for (std::uint32_t q = g.offset[std::size_t(j)]; q < g.offset[std::size_t(j) + 1]; ++q)
      if (int(g.neighbors[q]) > j)
        for (int r = 0; r < 4; ++r) t.emplace_back(4 * int(g.neighbors[q]) + r, 4 * j + r, -1.0 + 0.01 * r);
  }
  BlockCholesky::Matrix lower(4 * N, 4 * N);
  lower.setFromTriplets(t.begin(), t.end());
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(12 * N, -1, 2).array().sin();
  auto run = [&](int threads) {
    tbb::task_arena arena(threads);
    Eigen::VectorXd x = b;
    arena.execute([&] {
      BlockCholesky chol;
      chol.analyze(g.offset, g.neighbors);
      chol.factorize(lower);
      chol.solve3(x.data());
    });
    return x;
  };
  const Eigen::VectorXd x1 = run(1), x2 = run(2);
  EXPECT_EQ(0, std::memcmp(x1.data(), x2.data(), sizeof(double) * std::size_t(x1.size())));
  // And it solves: A x = b column by column of the interleaved layout.
  const BlockCholesky::Matrix A = lower.selfadjointView<Eigen::Lower>();
  Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>> X(x1.data(), 4 * N, 3), B(b.data(), 4 * N, 3);
  const Eigen::MatrixXd residual = A * Eigen::MatrixXd(X) - Eigen::MatrixXd(B);
  EXPECT_LT(residual.cwiseAbs().maxCoeff(), 1e-10);
}

TEST(BlockCholesky, BadInputThrows) {
  const Graph g = grid(3, 3);
  BlockCholesky chol;
  double x[36 * 3] = {};
  EXPECT_THROW(chol.solve3(x), SolverError);
  EXPECT_THROW(chol.analyze({0, 2}, {0}), InvalidInput);
  EXPECT_THROW(chol.analyze({0, 1}, {5}), InvalidInput);
  chol.analyze(g.offset, g.neighbors);
  EXPECT_THROW(chol.factorize(BlockCholesky::Matrix(8, 8)), InvalidInput);
  BlockCholesky::Matrix outside(36, 36), upper(36, 36);
  outside.insert(35, 0) = 1;  // nodes 0 and 8 are not neighbours
  EXPECT_THROW(chol.factorize(outside), InvalidInput);
  upper.insert(0, 1) = 1;
  EXPECT_THROW(chol.factorize(upper), InvalidInput);
  Eigen::MatrixXd A = random_spd(g, 1);
  A(5, 5) = -100;
  EXPECT_THROW(chol.factorize(lower_of(A)), SolverError);
  EXPECT_THROW(chol.solve3(x), SolverError);
}

}  // namespace
}  // namespace topotrack
