// hawor/matmul.hpp — the matrix products of the infiller network (motion/infiller_net.hpp) and of
// the batched hand forward pass (hand/forward.hpp): C = A·B (+ a bias row) with A row-major
// (activations, n×k: one frame per row) and B constant weights or per-head activations (k×m).
//
// Two backends, equal up to rounding (the order of the sums differs):
//   Eigen   Eigen's GEMM on row-major blocks: the native default (Eigen's SSE/AVX/AVX-512/NEON
//           kernels, about 70 GFLOP/s float on one AVX-512 core).
//   Packed  a register-blocked kernel in 16-byte vectors (GCC/Clang vector extensions) over B
//           packed once into column panels: the WebAssembly default. Eigen has no wasm SIMD
//           backend (DESIGN §9) and its scalar GEMM runs there at ~3 GFLOP/s; this kernel keeps
//           a 4×8 (float) / 4×4 (double) tile of C in 8 vector registers and streams
//           contiguous panels of A and B, which -msimd128 turns into v128 loads, f32x4/f64x2
//           multiplies and adds. Natively it is what the tests compare against Eigen.
//
// Layouts. PackedPanels holds B (k×m) as ceil(m/NR) panels of NR columns, each panel stored row
// by row (panel p, row r, column c at ((p·k + r)·NR + c)), zero-padded beyond column m. The
// packed kernel packs A the same way into ceil(n/MR) blocks of MR rows (block b, column r, row i
// at (b·k + r)·MR + i) in a caller-provided buffer, so a product allocates nothing.
// Thread-safety: Linear and PackedPanels are values; const member functions may run
// concurrently with distinct scratch buffers.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

#include "hawor/common.hpp"

namespace hawor {

/// Which implementation computes the network's matrix products (see the file comment).
enum class MatmulBackend { Eigen, Packed };

/// Eigen natively; the packed SIMD kernel under WebAssembly.
inline MatmulBackend defaultMatmulBackend() {
#if defined(__wasm__) || defined(__EMSCRIPTEN__)
  return MatmulBackend::Packed;
#else
  return MatmulBackend::Eigen;
#endif
}

/// Row-major dynamic matrix: the layout of the network's activations (T frames × features)
/// and of PyTorch's nn.Linear weights (out × in).
template <typename Scalar>
using RowMatrixX = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

namespace detail {

/// 16-byte vector of Scalar (4 floats, 2 doubles). With GCC/Clang vector extensions: native
/// SSE/NEON registers, wasm v128 under -msimd128. Elsewhere a plain array the compiler may
/// vectorise on its own. Loads/stores go through memcpy: no alignment is assumed.
template <typename Scalar>
struct Simd16 {
  static constexpr int lanes = 16 / static_cast<int>(sizeof(Scalar));
#if defined(__GNUC__) || defined(__clang__)
  typedef Scalar V __attribute__((vector_size(16)));
  static V splat(Scalar s) {
    if constexpr (lanes == 4) {
      return V{s, s, s, s};
    } else {
      return V{s, s};
    }
  }
  static V fma(V acc, V a, V b) { return acc + a * b; }
#else
  struct V {
    Scalar x[lanes];
  };
  static V splat(Scalar s) {
    V v;
    for (int i = 0; i < lanes; ++i) v.x[i] = s;
    return v;
  }
  static V fma(V acc, V a, V b) {
    for (int i = 0; i < lanes; ++i) acc.x[i] += a.x[i] * b.x[i];
    return acc;
  }
#endif
  static V load(const Scalar* p) {
    V v;
    std::memcpy(&v, p, sizeof(V));
    return v;
  }
  static void store(Scalar* p, V v) { std::memcpy(p, &v, sizeof(V)); }
};

}  // namespace detail

/// B (k×m) packed for the packed kernel (layout in the file comment). pack() reuses the
/// storage it already has, so re-packing per-head activations allocates nothing once reserved.
template <typename Scalar>
class PackedPanels {
 public:
  static constexpr int kLanes = detail::Simd16<Scalar>::lanes;
  /// Panel width: two vectors.
  static constexpr int kNR = 2 * kLanes;

  /// Capacity for a k×m matrix, so that later pack() calls up to that size do not allocate.
  void reserve(Eigen::Index k, Eigen::Index m) {
    data_.reserve(static_cast<size_t>(k * panelsFor(m) * kNR));
  }

  /// Packs B(r, j) = src[r·rowStride + j·colStride], r < k, j < m. Strides express a
  /// row-major matrix (rowStride = ld, colStride = 1) or the transpose of one (1, ld).
  void pack(const Scalar* src, Eigen::Index rowStride, Eigen::Index colStride, Eigen::Index k,
            Eigen::Index m) {
    k_ = k;
    m_ = m;
    const Eigen::Index panels = panelsFor(m);
    data_.resize(static_cast<size_t>(panels * k * kNR));
    Scalar* out = data_.data();
    for (Eigen::Index p = 0; p < panels; ++p) {
      const Eigen::Index j0 = p * kNR;
      const Eigen::Index w = std::min<Eigen::Index>(kNR, m - j0);
      for (Eigen::Index r = 0; r < k; ++r) {
        const Scalar* row = src + r * rowStride + j0 * colStride;
        Eigen::Index c = 0;
        for (; c < w; ++c) out[c] = row[c * colStride];
        for (; c < kNR; ++c) out[c] = Scalar(0);
        out += kNR;
      }
    }
  }

  Eigen::Index rows() const { return k_; }
  Eigen::Index cols() const { return m_; }
  const Scalar* panel(Eigen::Index p) const { return data_.data() + p * k_ * kNR; }
  static Eigen::Index panelsFor(Eigen::Index m) { return (m + kNR - 1) / kNR; }

 private:
  Eigen::Index k_ = 0, m_ = 0;
  std::vector<Scalar> data_;
};

/// Rows per register tile of the packed kernel.
constexpr int kPackedMR = 4;

/// Size of the A-packing buffer matmulPacked needs for n rows of k columns.
inline Eigen::Index packedScratchSize(Eigen::Index n, Eigen::Index k) {
  return (n + kPackedMR - 1) / kPackedMR * kPackedMR * k;
}

/// C(n×m) = A(n×k)·B (+ bias, m values, when not null), packed kernel. A and C row-major with
/// leading dimensions lda, ldc; `apack` holds packedScratchSize(n, k) values.
template <typename Scalar>
void matmulPacked(const Scalar* A, Eigen::Index lda, Eigen::Index n, const PackedPanels<Scalar>& B,
                  Scalar* C, Eigen::Index ldc, const Scalar* bias, Scalar* apack) {
  using S = detail::Simd16<Scalar>;
  using V = typename S::V;
  constexpr int MR = kPackedMR;
  constexpr int L = S::lanes;
  constexpr int NR = PackedPanels<Scalar>::kNR;
  const Eigen::Index k = B.rows(), m = B.cols();
  const Eigen::Index blocks = (n + MR - 1) / MR;
  // A into blocks of MR rows, column by column (zero rows past n).
  for (Eigen::Index b = 0; b < blocks; ++b) {
    Scalar* dst = apack + b * k * MR;
    for (int i = 0; i < MR; ++i) {
      const Eigen::Index row = b * MR + i;
      if (row < n) {
        const Scalar* a = A + row * lda;
        for (Eigen::Index r = 0; r < k; ++r) dst[r * MR + i] = a[r];
      } else {
        for (Eigen::Index r = 0; r < k; ++r) dst[r * MR + i] = Scalar(0);
      }
    }
  }
  // k in slices of kKC: a slice of a B panel (kKC·NR values, 8 KiB) stays in L1 while every
  // row block runs over it; C is the running sum between slices.
  constexpr Eigen::Index kKC = 256;
  Scalar biasPanel[NR];
  Scalar tile[MR * NR];
  const Eigen::Index panels = PackedPanels<Scalar>::panelsFor(m);
  const Eigen::Index slices = std::max<Eigen::Index>(1, (k + kKC - 1) / kKC);  // k = 0: C = bias
  for (Eigen::Index slice = 0; slice < slices; ++slice) {
    const Eigen::Index k0 = slice * kKC;
    const Eigen::Index kc = std::min(kKC, k - k0);
    for (Eigen::Index p = 0; p < panels; ++p) {
      const Eigen::Index j0 = p * NR;
      const Eigen::Index w = std::min<Eigen::Index>(NR, m - j0);
      for (int c = 0; c < NR; ++c) biasPanel[c] = (bias && c < w) ? bias[j0 + c] : Scalar(0);
      const Scalar* bp = B.panel(p) + k0 * NR;
      for (Eigen::Index b = 0; b < blocks; ++b) {
        const Eigen::Index rows = std::min<Eigen::Index>(MR, n - b * MR);
        const bool full = rows == MR && w == NR;
        Scalar* cRow = C + b * MR * ldc + j0;
        // the accumulators start from the bias (first slice) or from the partial sums in C
        V acc[MR][2];
        for (int i = 0; i < MR; ++i) {
          const Scalar* src = biasPanel;
          if (k0 > 0 && full) {
            src = cRow + i * ldc;
          } else if (k0 > 0) {
            for (int c = 0; c < NR; ++c)
              tile[i * NR + c] = (i < rows && c < w) ? cRow[i * ldc + c] : Scalar(0);
            src = tile + i * NR;
          }
          acc[i][0] = S::load(src);
          acc[i][1] = S::load(src + L);
        }
        const Scalar* ap = apack + (b * k + k0) * MR;
        const Scalar* bq = bp;
        for (Eigen::Index r = 0; r < kc; ++r, ap += MR, bq += NR) {
          const V b0 = S::load(bq), b1 = S::load(bq + L);
          for (int i = 0; i < MR; ++i) {
            const V a = S::splat(ap[i]);
            acc[i][0] = S::fma(acc[i][0], a, b0);
            acc[i][1] = S::fma(acc[i][1], a, b1);
          }
        }
        if (full) {
          for (int i = 0; i < MR; ++i) {
            S::store(cRow + i * ldc, acc[i][0]);
            S::store(cRow + i * ldc + L, acc[i][1]);
          }
        } else {  // edge tile: through the buffer, only the rows and columns that exist
          for (int i = 0; i < MR; ++i) {
            S::store(tile + i * NR, acc[i][0]);
            S::store(tile + i * NR + L, acc[i][1]);
          }
          for (Eigen::Index i = 0; i < rows; ++i)
            for (Eigen::Index c = 0; c < w; ++c) cRow[i * ldc + c] = tile[i * NR + c];
        }
      }
    }
  }
}

/// A fully connected layer y = x·Wᵀ + b (PyTorch nn.Linear, W out×in), applied to every row of
/// a row-major activation block. Holds W in the form its backend wants: as given (Eigen) or
/// packed as Wᵀ (Packed), never both.
template <typename Scalar>
class Linear {
 public:
  Linear() = default;

  /// `weight` out×in; `bias` of length out, or empty for no bias.
  Linear(const RowMatrixX<Scalar>& weight, const VecX<Scalar>& bias, MatmulBackend backend)
      : backend_(backend), in_(weight.cols()), out_(weight.rows()), bias_(bias) {
    if (bias.size() != 0 && bias.size() != weight.rows())
      throw Error("Linear: bias has " + std::to_string(bias.size()) + " values for " +
                  std::to_string(weight.rows()) + " outputs");
    if (backend == MatmulBackend::Eigen) {
      weight_ = weight;
    } else {
      packed_.pack(weight.data(), 1, weight.cols(), weight.cols(), weight.rows());  // Wᵀ
    }
  }

  Eigen::Index inDim() const { return in_; }
  Eigen::Index outDim() const { return out_; }
  MatmulBackend backend() const { return backend_; }

  /// Y = X·Wᵀ + b for the n rows of X (n×in) into Y (n×out): row-major blocks with unit inner
  /// stride (e.g. topRows / middleCols of a RowMatrixX). `scratch` holds packedScratchSize(n,
  /// in) values (unused by the Eigen backend).
  template <typename XD, typename YD>
  void apply(const Eigen::MatrixBase<XD>& X, const Eigen::MatrixBase<YD>& Yc,
             Scalar* scratch) const {
    Eigen::MatrixBase<YD>& Y = const_cast<Eigen::MatrixBase<YD>&>(Yc);
    if (X.cols() != in_ || Y.cols() != out_ || Y.rows() != X.rows())
      throw Error("Linear: " + std::to_string(X.rows()) + "x" + std::to_string(X.cols()) +
                  " input, " + std::to_string(Y.rows()) + "x" + std::to_string(Y.cols()) +
                  " output for a " + std::to_string(in_) + " -> " + std::to_string(out_) +
                  " layer");
    if (backend_ == MatmulBackend::Eigen) {
      Y.noalias() = X * weight_.transpose();
      if (bias_.size() != 0) Y.rowwise() += bias_.transpose();
    } else {
      static_assert(XD::IsRowMajor && YD::IsRowMajor, "Linear: row-major blocks expected");
      if (X.derived().innerStride() != 1 || Y.derived().innerStride() != 1)
        throw Error("Linear: blocks with contiguous rows expected");
      matmulPacked(X.derived().data(), X.derived().outerStride(), X.rows(), packed_,
                   Y.derived().data(), Y.derived().outerStride(),
                   bias_.size() != 0 ? bias_.data() : nullptr, scratch);
    }
  }

 private:
  MatmulBackend backend_ = MatmulBackend::Eigen;
  Eigen::Index in_ = 0, out_ = 0;
  RowMatrixX<Scalar> weight_;
  VecX<Scalar> bias_;
  PackedPanels<Scalar> packed_;
};

}  // namespace hawor
