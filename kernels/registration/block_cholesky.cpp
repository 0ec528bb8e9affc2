#include "kernels/registration/block_cholesky.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Cholesky>
#include <Eigen/OrderingMethods>
#include <algorithm>
#include <cmath>

#include "io/error.hpp"

namespace topotrack {

using Block = Eigen::Matrix4d;                               // column-major 4 x 4
using Rows3 = Eigen::Matrix<double, 4, 3, Eigen::RowMajor>;  // a node's rows of the 4N x 3 right-hand side

namespace {

// Subtrees below this many blocks of L, or below an eighth of the whole, are processed by one task:
// few synchronisation points per solve (a task waiting for a descheduled one stalls on a busy machine).
constexpr int kSerialWork = 4096;

inline std::size_t at(int i) { return std::size_t(i); }

}  // namespace

struct BlockCholesky::Impl {
  int nodes = 0;
  std::vector<int> order;      // new node -> old node (minimum degree, then elimination-tree postorder)
  std::vector<int> new_index;  // old node -> new node
  // Block pattern of L below the diagonal, by columns (rows ascending) and by rows (columns ascending,
  // with the position of the block in the column storage).
  std::vector<int> block_outer, block_row;
  std::vector<int> row_outer, row_col, row_block;
  // Elimination tree in postorder: the subtree of a is first[a] .. a; work: blocks of L in it.
  std::vector<int> child_outer, child, roots, first, work;
  int serial_work = kSerialWork;
  // Numeric factor L L^T: the inverse of each (lower triangular) diagonal block, and the blocks below.
  std::vector<Block> diag_inverse, value;
  std::vector<Block> row_value;  // value in row order, for the forward solve to stream through
  bool factorized = false;

  // Visit every node, children before parents (`up`) or parents before children (down), subtrees in
  // parallel. The visit of a node may only depend on its subtree (up) or its ancestors (down), so the
  // result does not depend on the scheduling.
  template <class F>
  void up(int a, const F& visit) const {
    std::vector<int> chain;
    for (int x = a;;) {
      if (work[at(x)] < serial_work) {
        for (int i = first[at(x)]; i <= x; ++i) visit(i);
        break;
      }
      const int c0 = child_outer[at(x)], nc = child_outer[at(x) + 1] - c0;
      if (nc == 1) {
        chain.push_back(x);
        x = child[at(c0)];
        continue;
      }
      tbb::parallel_for(0, nc, 1, [&](int k) { up(child[at(c0 + k)], visit); });
      visit(x);
      break;
    }
    for (auto it = chain.rbegin(); it != chain.rend(); ++it) visit(*it);
  }
  template <class F>
  void down(int a, const F& visit) const {
    for (int x = a;;) {
      if (work[at(x)] < serial_work) {
        for (int i = x; i >= first[at(x)]; --i) visit(i);
        return;
      }
      visit(x);
      const int c0 = child_outer[at(x)], nc = child_outer[at(x) + 1] - c0;
      if (nc != 1) {
        tbb::parallel_for(0, nc, 1, [&](int k) { down(child[at(c0 + k)], visit); });
        return;
      }
      x = child[at(c0)];
    }
  }
  template <class F>
  void all_up(const F& visit) const {
    tbb::parallel_for(0, int(roots.size()), 1, [&](int k) { up(roots[at(k)], visit); });
  }
  template <class F>
  void all_down(const F& visit) const {
    tbb::parallel_for(0, int(roots.size()), 1, [&](int k) { down(roots[at(k)], visit); });
  }
};

BlockCholesky::BlockCholesky() : impl_(std::make_unique<Impl>()) {}
BlockCholesky::~BlockCholesky() = default;
BlockCholesky::BlockCholesky(BlockCholesky&&) noexcept = default;
BlockCholesky& BlockCholesky::operator=(BlockCholesky&&) noexcept = default;

void BlockCholesky::analyze(const std::vector<std::uint32_t>& offset, const std::vector<std::uint32_t>& neighbors) {
  if (offset.empty() || offset.back() != neighbors.size())
    TT_THROW(InvalidInput, "BlockCholesky: malformed graph (" << offset.size() << " offsets, " << neighbors.size()
                                                              << " neighbours)");
  Impl& m = *impl_;
  const int N = int(offset.size() - 1);
  m.nodes = N;
  m.factorized = false;
  // Approximate minimum degree on the node graph (AMD's output lists the old nodes in elimination order).
  std::vector<Eigen::Triplet<double, int>> entries;
  entries.reserve(at(N) + neighbors.size());
  for (int j = 0; j < N; ++j) {
    entries.emplace_back(j, j, 1.0);
    for (std::uint32_t q = offset[at(j)]; q < offset[at(j) + 1]; ++q) {
      if (neighbors[q] >= std::uint32_t(N)) TT_THROW(InvalidInput, "BlockCholesky: neighbour " << neighbors[q] << " out of range");
      entries.emplace_back(int(neighbors[q]), j, 1.0);
    }
  }
  Matrix graph(N, N);
  graph.setFromTriplets(entries.begin(), entries.end());
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> amd;
  Eigen::AMDOrdering<int>()(graph, amd);
  m.order.assign(amd.indices().data(), amd.indices().data() + N);

  // Elimination tree of the order (Liu's algorithm with path compression).
  std::vector<int> parent(at(N)), ancestor(at(N)), mark(at(N));
  std::vector<std::vector<int>> lower_adj(static_cast<std::size_t>(N));
  auto elimination_tree = [&] {
    m.new_index.assign(at(N), 0);
    for (int a = 0; a < N; ++a) m.new_index[at(m.order[at(a)])] = a;
    for (auto& l : lower_adj) l.clear();
    for (int j = 0; j < N; ++j)
      for (std::uint32_t q = offset[at(j)]; q < offset[at(j) + 1]; ++q) {
        const int a = m.new_index[at(j)], b = m.new_index[neighbors[q]];
        if (b < a) lower_adj[at(a)].push_back(b);
      }
    std::fill(parent.begin(), parent.end(), -1);
    std::fill(ancestor.begin(), ancestor.end(), -1);
    for (int k = 0; k < N; ++k)
      for (int i : lower_adj[at(k)]) {
        int r = i;
        while (ancestor[at(r)] != -1 && ancestor[at(r)] != k) {
          const int next = ancestor[at(r)];
          ancestor[at(r)] = k;
          r = next;
        }
        if (ancestor[at(r)] == -1) {
          ancestor[at(r)] = k;
          parent[at(r)] = k;
        }
      }
  };
  auto build_children = [&] {
    m.child_outer.assign(at(N) + 1, 0);
    m.roots.clear();
    for (int a = 0; a < N; ++a)
      if (parent[at(a)] >= 0) ++m.child_outer[at(parent[at(a)]) + 1];
      else m.roots.push_back(a);
    for (int a = 0; a < N; ++a) m.child_outer[at(a) + 1] += m.child_outer[at(a)];
    m.child.assign(at(m.child_outer[at(N)]), 0);
    std::vector<int> fill(m.child_outer.begin(), m.child_outer.end() - 1);
    for (int a = 0; a < N; ++a)
      if (parent[at(a)] >= 0) m.child[at(fill[at(parent[at(a)])]++)] = a;  // ascending
  };
  elimination_tree();
  build_children();
  // Renumber in postorder (same fill): every subtree becomes a contiguous range.
  {
    std::vector<int> post_order;
    post_order.reserve(at(N));
    std::vector<std::pair<int, int>> stack;  // node, next child
    for (int r : m.roots) {
      stack.emplace_back(r, m.child_outer[at(r)]);
      while (!stack.empty()) {
        auto& [x, c] = stack.back();
        if (c < m.child_outer[at(x) + 1]) {
          const int y = m.child[at(c++)];
          stack.emplace_back(y, m.child_outer[at(y)]);
        } else {
          post_order.push_back(x);
          stack.pop_back();
        }
      }
    }
    std::vector<int> order(at(N));
    for (int a = 0; a < N; ++a) order[at(a)] = m.order[at(post_order[at(a)])];
    m.order.swap(order);
  }
  elimination_tree();
  build_children();

  // Pattern of each row of L: the tree paths from the row's neighbours below the diagonal up to the row.
  std::vector<int> count(at(N) + 1, 0);
  auto walk_rows = [&](auto&& visit) {
    std::fill(mark.begin(), mark.end(), -1);
    for (int k = 0; k < N; ++k) {
      mark[at(k)] = k;
      for (int i : lower_adj[at(k)])
        for (int j = i; mark[at(j)] != k; j = parent[at(j)]) {
          visit(j, k);  // L(k, j) != 0
          mark[at(j)] = k;
        }
    }
  };
  walk_rows([&](int j, int) { ++count[at(j) + 1]; });
  for (int j = 0; j < N; ++j) count[at(j) + 1] += count[at(j)];
  m.block_outer = count;
  m.block_row.assign(at(count[at(N)]), 0);
  walk_rows([&](int j, int k) { m.block_row[at(count[at(j)]++)] = k; });  // k ascending
  m.row_outer.assign(at(N) + 1, 0);
  for (int r : m.block_row) ++m.row_outer[at(r) + 1];
  for (int a = 0; a < N; ++a) m.row_outer[at(a) + 1] += m.row_outer[at(a)];
  m.row_col.assign(m.block_row.size(), 0);
  m.row_block.assign(m.block_row.size(), 0);
  std::vector<int> fill(m.row_outer.begin(), m.row_outer.end() - 1);
  for (int a = 0; a < N; ++a)
    for (int q = m.block_outer[at(a)]; q < m.block_outer[at(a) + 1]; ++q) {
      const int p = fill[at(m.block_row[at(q)])]++;
      m.row_col[at(p)] = a;
      m.row_block[at(p)] = q;
    }
  m.first.assign(at(N), 0);
  m.work.assign(at(N), 0);
  for (int a = 0; a < N; ++a) {  // children precede parents
    m.work[at(a)] += 1 + m.block_outer[at(a) + 1] - m.block_outer[at(a)];
    const int c0 = m.child_outer[at(a)];
    m.first[at(a)] = c0 < m.child_outer[at(a) + 1] ? m.first[at(m.child[at(c0)])] : a;
    if (parent[at(a)] >= 0) m.work[at(parent[at(a)])] += m.work[at(a)];
  }
  long total = 0;
  for (int r : m.roots) total += m.work[at(r)];
  m.serial_work = int(std::max<long>(kSerialWork, total / 8));
}

void BlockCholesky::factorize(const Matrix& lower) {
  Impl& m = *impl_;
  const int N = m.nodes, n = 4 * N;
  if (lower.rows() != n || lower.cols() != n)
    TT_THROW(InvalidInput, "BlockCholesky: a " << lower.rows() << " x " << lower.cols() << " matrix for " << N << " nodes");
  m.factorized = false;
  m.diag_inverse.assign(at(N), Block::Zero());
  m.value.assign(m.block_row.size(), Block::Zero());
  std::vector<Block> diag(at(N), Block::Zero());
  auto find = [&](int col, int row) {  // position of block (row, col) of L, or -1
    const auto b = m.block_row.begin() + m.block_outer[at(col)], e = m.block_row.begin() + m.block_outer[at(col) + 1];
    const auto it = std::lower_bound(b, e, row);
    return it != e && *it == row ? int(it - m.block_row.begin()) : -1;
  };
  // Scatter A into the pattern of L (the diagonal blocks kept apart, both triangles).
  for (int j = 0; j < n; ++j)
    for (Matrix::InnerIterator it(lower, j); it; ++it) {
      const int i = int(it.row());
      if (i < j) TT_THROW(InvalidInput, "BlockCholesky: entry (" << i << ", " << j << ") above the diagonal");
      const int a = m.new_index[at(j / 4)], b = m.new_index[at(i / 4)], r = i % 4, c = j % 4;
      if (a == b) {
        diag[at(a)](r, c) += it.value();
        if (r != c) diag[at(a)](c, r) += it.value();
        continue;
      }
      const int q = a < b ? find(a, b) : find(b, a);
      if (q < 0) TT_THROW(InvalidInput, "BlockCholesky: entry (" << i << ", " << j << ") outside the graph's blocks");
      if (a < b) m.value[at(q)](r, c) += it.value();
      else m.value[at(q)](c, r) += it.value();
    }
  // Left-looking block Cholesky: column a gathers the updates of the columns d of its row pattern
  // (all in a's subtree), then is scaled by its diagonal block. Subtrees in parallel.
  std::vector<char> ok(at(N), 1);
  m.all_up([&](int a) {
    const int first = m.block_outer[at(a)], end = m.block_outer[at(a) + 1];
    Block C = diag[at(a)];
    for (int p = m.row_outer[at(a)]; p < m.row_outer[at(a) + 1]; ++p) {
      const int d = m.row_col[at(p)], qa = m.row_block[at(p)], dend = m.block_outer[at(d) + 1];
      const Block Lad = m.value[at(qa)];
      C.noalias() -= Lad * Lad.transpose();
      // Rows below a in column d are a subset of column a's rows (both ascending): merge.
      int q = first;
      for (int qd = qa + 1; qd < dend; ++qd) {
        const int row = m.block_row[at(qd)];
        while (m.block_row[at(q)] < row) ++q;
        m.value[at(q)].noalias() -= m.value[at(qd)] * Lad.transpose();
      }
    }
    const Eigen::LLT<Block> llt(C);
    if (llt.info() != Eigen::Success || !(llt.matrixLLT().diagonal().minCoeff() > 0) || !llt.matrixLLT().allFinite()) {
      ok[at(a)] = 0;
      m.diag_inverse[at(a)] = Block::Identity();
      return;
    }
    const Block Linv = llt.matrixL().solve(Block::Identity());
    m.diag_inverse[at(a)] = Linv;
    for (int q = first; q < end; ++q) m.value[at(q)] = (m.value[at(q)] * Linv.transpose()).eval();
  });
  if (std::find(ok.begin(), ok.end(), 0) != ok.end())
    TT_THROW(SolverError, "BlockCholesky: factorisation of a " << n << " x " << n << " system failed (not positive definite)");
  m.row_value.resize(m.value.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m.value.size(), 4096), [&](const auto& r) {
    for (std::size_t p = r.begin(); p != r.end(); ++p) m.row_value[p] = m.value[at(m.row_block[p])];
  });
  m.factorized = true;
}

void BlockCholesky::solve3(double* x) const {
  const Impl& m = *impl_;
  if (!m.factorized) TT_THROW(SolverError, "BlockCholesky: solve before a successful factorisation");
  const int N = m.nodes;
  std::vector<Rows3> y(static_cast<std::size_t>(N));
  for (int a = 0; a < N; ++a) y[at(a)] = Eigen::Map<const Rows3>(x + 12 * at(m.order[at(a)]));
  // L y = b by rows (row a only reads its subtree), then L^T x = y by columns (column a only reads its
  // ancestors).
  m.all_up([&](int a) {
    Rows3 s = y[at(a)];
    for (int p = m.row_outer[at(a)]; p < m.row_outer[at(a) + 1]; ++p)
      s.noalias() -= m.row_value[at(p)] * y[at(m.row_col[at(p)])];
    y[at(a)] = m.diag_inverse[at(a)] * s;
  });
  m.all_down([&](int a) {
    Rows3 s = y[at(a)];
    for (int q = m.block_outer[at(a)]; q < m.block_outer[at(a) + 1]; ++q)
      s.noalias() -= m.value[at(q)].transpose() * y[at(m.block_row[at(q)])];
    y[at(a)] = m.diag_inverse[at(a)].transpose() * s;
  });
  bool finite = true;
  for (int a = 0; a < N; ++a) {
    finite = finite && y[at(a)].allFinite();
    Eigen::Map<Rows3>(x + 12 * at(m.order[at(a)])) = y[at(a)];
  }
  if (!finite) TT_THROW(SolverError, "BlockCholesky: solve of a " << 4 * N << " x 3 system failed");
}

std::size_t BlockCholesky::factor_nonzeros() const {
  return 10 * at(impl_->nodes) + 16 * impl_->block_row.size();
}

}  // namespace topotrack
