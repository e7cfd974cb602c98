// hawor/matmul.hpp — the matrix products of the infiller network (motion/infiller_net.hpp) and of
// the batched hand forward pass (hand/forward.hpp): C = A·B (+ a bias row) with A row-major
// (activations, n×k: one frame per row) and B constant weights or per-head activations (k×m).
//
// Three backends, equal up to rounding (the order of the sums differs; AMX rounds its inputs):
//   Eigen   Eigen's GEMM on row-major blocks: the native default (Eigen's SSE/AVX/AVX-512/NEON
//           kernels, about 70 GFLOP/s float on one AVX-512 core).
//   Packed  a register-blocked kernel in 16-byte vectors (GCC/Clang vector extensions) over B
//           packed once into column panels: the WebAssembly default. Eigen has no wasm SIMD
//           backend (docs/design.md §9) and its scalar GEMM runs there at ~3 GFLOP/s; this kernel keeps
//           a 4×8 (float) / 4×4 (double) tile of C in 8 vector registers and streams
//           contiguous panels of A and B, which -msimd128 turns into v128 loads, f32x4/f64x2
//           multiplies and adds. Natively it is what the tests compare against Eigen.
//   Amx     float only, x86-64 Linux builds compiled with AMX (-mamx-tile -mamx-bf16, e.g.
//           -march=native on Sapphire Rapids) on a CPU and kernel that allow it (amxAvailable()):
//           Intel AMX tiles (TDPBF16PS, bf16 products accumulated in fp32) with the bf16x3 split
//           a = a_hi + a_lo (a_hi = bf16(a), a_lo = bf16(a − a_hi)), A·B ≈ A_hi·B_hi + A_hi·B_lo +
//           A_lo·B_hi: 16 of fp32's 24 significant bits per operand, relative error per product
//           ~1e-5 (plain fp32 ~1e-7). AmxBf16 is the plain-bf16 product A_hi·B_hi (one tile
//           product instead of three, error ~4e-3 relative): measured, not a default.
//   Auto    Amx where available (float), else the platform default above: the infiller's default.
// A backend that cannot run here (Amx on a build without AMX, on another CPU, where Linux refuses
// the tile state, or for double) resolves to defaultMatmulBackend(): resolveMatmulBackend().
//
// Layouts. PackedPanels holds B (k×m) as ceil(m/NR) panels of NR columns, each panel stored row
// by row (panel p, row r, column c at ((p·k + r)·NR + c)), zero-padded beyond column m. The
// packed kernel packs A the same way into ceil(n/MR) blocks of MR rows (block b, column r, row i
// at (b·k + r)·MR + i) in a caller-provided buffer, so a product allocates nothing. AmxPanels
// and the AMX kernel's A packing are described at AmxPanels.
// Thread-safety: Linear, PackedPanels and AmxPanels are values; const member functions may run
// concurrently with distinct scratch buffers (each thread loads its own tile configuration).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

// GCC names the AMX feature macros __AMX_TILE__ / __AMX_BF16__, clang 14 __AMXTILE__ / __AMXBF16__.
#if (defined(__AMX_TILE__) || defined(__AMXTILE__)) && (defined(__AMX_BF16__) || defined(__AMXBF16__)) && \
    defined(__x86_64__) && defined(__linux__)
#define HAWOR_HAS_AMX 1
#include <cpuid.h>
#include <immintrin.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

#include "hawor/common.hpp"

namespace hawor {

/// Which implementation computes the network's matrix products (see the file comment).
enum class MatmulBackend { Eigen, Packed, Amx, AmxBf16, Auto };

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

/// A backend's name, as the benchmarks and tests print it.
inline const char* matmulBackendName(MatmulBackend b) {
  switch (b) {
    case MatmulBackend::Eigen:
      return "Eigen";
    case MatmulBackend::Packed:
      return "Packed";
    case MatmulBackend::Amx:
      return "Amx";
    case MatmulBackend::AmxBf16:
      return "AmxBf16";
    default:
      return "Auto";
  }
}

namespace detail {

#if defined(HAWOR_HAS_AMX)
/// CPUID (AMX-TILE, AMX-BF16, and AVX-512F + AVX512-BF16 for the A packing, OSXSAVE), XCR0 (the
/// OS enabled the tile and ZMM states) and the Linux permission for the tile data state
/// (arch_prctl(ARCH_REQ_XCOMP_PERM, XFEATURE_XTILEDATA), Linux ≥ 5.16; process-wide, so once).
inline bool amxRuntimeCheck() {
  unsigned a = 0, b = 0, c = 0, d = 0;
  if (!__get_cpuid(1, &a, &b, &c, &d) || !((c >> 27) & 1u)) return false;  // OSXSAVE
  if (__get_cpuid_max(0, nullptr) < 7) return false;
  __cpuid_count(7, 0, a, b, c, d);
  if (!((d >> 24) & 1u) || !((d >> 22) & 1u)) return false;  // AMX-TILE, AMX-BF16
  if (!((b >> 16) & 1u)) return false;                       // AVX-512F
  __cpuid_count(7, 1, a, b, c, d);
  if (!((a >> 5) & 1u)) return false;  // AVX512-BF16
  unsigned lo = 0, hi = 0;
  __asm__ volatile("xgetbv" : "=a"(lo), "=d"(hi) : "c"(0));
  // XCR0: SSE, AVX, opmask, ZMM (bits 1, 2, 5–7) and XTILECFG, XTILEDATA (17, 18)
  const unsigned need = 0x6u | 0xe0u | (3u << 17);
  if ((lo & need) != need) return false;
  constexpr long kArchGetXcompPerm = 0x1022, kArchReqXcompPerm = 0x1023, kXtileData = 18;
  if (syscall(SYS_arch_prctl, kArchReqXcompPerm, kXtileData) != 0) return false;
  unsigned long long perm = 0;
  return syscall(SYS_arch_prctl, kArchGetXcompPerm, &perm) == 0 && ((perm >> kXtileData) & 1u);
}
#endif

// bf16 values as stored for the AMX kernel: uint16 that may alias the float scratch buffers the
// callers hand in (Linear::apply's `scratch`).
#if defined(__GNUC__) || defined(__clang__)
typedef std::uint16_t Bf16 __attribute__((may_alias));
#else
typedef std::uint16_t Bf16;
#endif

/// float → bf16, rounded to nearest even (what VCVTNEPS2BF16 does; a NaN stays a NaN).
inline std::uint16_t bf16Round(float x) {
  std::uint32_t u;
  std::memcpy(&u, &x, sizeof u);
  const std::uint32_t rounded = (u + 0x7fffu + ((u >> 16) & 1u)) >> 16;
  const std::uint32_t quietNan = (u >> 16) | 0x40u;
  return static_cast<std::uint16_t>((u & 0x7fffffffu) > 0x7f800000u ? quietNan : rounded);
}

inline float bf16ToFloat(std::uint16_t h) {
  const std::uint32_t u = std::uint32_t(h) << 16;
  float x;
  std::memcpy(&x, &u, sizeof x);
  return x;
}

/// x ≈ hi + lo with hi = bf16(x), lo = bf16(x − hi) (x − hi is exact in float): 16 significant
/// bits, |x − hi − lo| ≤ 2⁻¹⁷·|x| (denormal lo aside, which TDPBF16PS reads as 0).
inline void bf16Split(float x, Bf16* hi, Bf16* lo) {
  const std::uint16_t h = bf16Round(x);
  *hi = h;
  *lo = bf16Round(x - bf16ToFloat(h));
}

}  // namespace detail

/// Whether the AMX kernel can run here: compiled in (an x86-64 Linux build with -mamx-tile
/// -mamx-bf16, e.g. -march=native on Sapphire Rapids or later), the CPU has AMX-TILE and
/// AMX-BF16, and the OS enabled the tile state and granted it to this process. Checked once.
/// HAWOR_AMX=0 in the environment answers false (forces the fallback backend).
inline bool amxAvailable() {
#if defined(HAWOR_HAS_AMX)
  static const bool ok = [] {
    const char* env = std::getenv("HAWOR_AMX");
    if (env && std::strcmp(env, "0") == 0) return false;
    return detail::amxRuntimeCheck();
  }();
  return ok;
#else
  return false;
#endif
}

/// The backend that computes Scalar products when `requested` is asked for: Eigen and Packed as
/// they are; Amx and AmxBf16 where amxAvailable() and Scalar is float, else
/// defaultMatmulBackend(); Auto = Amx where that runs, else defaultMatmulBackend().
template <typename Scalar>
MatmulBackend resolveMatmulBackend(MatmulBackend requested) {
  const bool amx = std::is_same<Scalar, float>::value && amxAvailable();
  switch (requested) {
    case MatmulBackend::Eigen:
    case MatmulBackend::Packed:
      return requested;
    case MatmulBackend::Amx:
    case MatmulBackend::AmxBf16:
      return amx ? requested : defaultMatmulBackend();
    default:
      return amx ? MatmulBackend::Amx : defaultMatmulBackend();
  }
}

/// B (k×m, float) for the AMX kernel: split into bf16 hi and lo parts (detail::bf16Split) and
/// laid out as TDPBF16PS reads its second operand. k runs in steps of 32 (zero-padded), m in
/// panels of 16 columns taken two at a time (zero columns past m; a zero panel where the count
/// is odd). Block (q, s) — panel pair q, k step s — is 4 tiles of 16 rows × 64 bytes: hi of
/// panel 2q, lo of panel 2q, hi of panel 2q+1, lo of panel 2q+1, each 512 values; row r of a
/// tile holds, for its 16 columns c, the pair B(32s + 2r, c), B(32s + 2r + 1, c) (the "VNNI"
/// pair layout). Blocks follow each other, q major, so the kernel reads B in order. Same size as
/// B in float (2 × 2 bytes a value). Portable code (only the kernel needs AMX).
class AmxPanels {
 public:
  static constexpr int kTile = 16;   // rows of a tile, and float columns of a C tile
  static constexpr int kKStep = 32;  // bf16 values in a 64-byte tile row
  static constexpr int kTileValues = kTile * kKStep;  // 512 bf16: one tile

  /// Packs B(r, j) = src[r·rowStride + j·colStride], r < k, j < m (as PackedPanels::pack).
  void pack(const float* src, Eigen::Index rowStride, Eigen::Index colStride, Eigen::Index k,
            Eigen::Index m) {
    k_ = k;
    m_ = m;
    steps_ = (k + kKStep - 1) / kKStep;
    pairs_ = (m + 2 * kTile - 1) / (2 * kTile);
    data_.assign(static_cast<size_t>(pairs_ * steps_ * 4 * kTileValues), 0);
    for (Eigen::Index q = 0; q < pairs_; ++q)
      for (Eigen::Index s = 0; s < steps_; ++s)
        for (int p = 0; p < 2; ++p) {
          detail::Bf16* hi = data_.data() + ((q * steps_ + s) * 4 + 2 * p) * kTileValues;
          detail::Bf16* lo = hi + kTileValues;
          for (int r = 0; r < kKStep; ++r) {
            const Eigen::Index row = s * kKStep + r;
            if (row >= k) break;
            for (int c = 0; c < kTile; ++c) {
              const Eigen::Index col = (2 * q + p) * kTile + c;
              if (col >= m) break;
              const int at = (r / 2) * 2 * kTile + 2 * c + (r % 2);
              detail::bf16Split(src[row * rowStride + col * colStride], hi + at, lo + at);
            }
          }
        }
  }

  Eigen::Index rows() const { return k_; }
  Eigen::Index cols() const { return m_; }
  Eigen::Index kSteps() const { return steps_; }
  Eigen::Index panelPairs() const { return pairs_; }
  /// Block (q, s): 4 tiles (see the class comment).
  const std::uint16_t* block(Eigen::Index q, Eigen::Index s) const {
    return data_.data() + (q * steps_ + s) * 4 * kTileValues;
  }

 private:
  Eigen::Index k_ = 0, m_ = 0, steps_ = 0, pairs_ = 0;
  std::vector<std::uint16_t> data_;
};

/// Size, in floats, of the A-packing buffer the AMX kernel needs for n rows of k columns:
/// ceil(n/32)·32 rows × ceil(k/32)·32 columns of bf16 hi and lo (2 × 2 bytes = one float).
inline Eigen::Index amxScratchSize(Eigen::Index n, Eigen::Index k) {
  return (n + 31) / 32 * 32 * ((k + 31) / 32 * 32);
}

/// Scratch size (in Scalar values) that covers every backend's product of n rows of k columns.
inline Eigen::Index matmulScratchSize(Eigen::Index n, Eigen::Index k) {
  return std::max(packedScratchSize(n, k), amxScratchSize(n, k));
}

#if defined(HAWOR_HAS_AMX)
namespace detail {

/// The 64-byte operand of LDTILECFG (palette 1): bytes 16–47 the bytes per row of tiles 0–15,
/// bytes 48–63 their rows.
struct alignas(64) AmxTileConfig {
  std::uint8_t palette = 1;
  std::uint8_t startRow = 0;
  std::uint8_t reserved[14] = {};
  std::uint16_t colsb[16] = {};
  std::uint8_t rows[16] = {};
};

// GCC's AMX intrinsics are asm statements that tell the compiler nothing about the memory they
// read or write: this barrier keeps plain loads and stores of the buffers they touch in order.
inline void compilerBarrier() { __asm__ volatile("" ::: "memory"); }

/// Packs the rows [0, n) of A (n×k, leading dimension lda) for the AMX kernel: row tile t (16
/// rows), k step s (32 columns) at apack + (t·steps + s)·1024: the hi tile (row i, column c at
/// i·32 + c), then the lo tile; zeros past row n (up to a multiple of 32) and column k. AVX-512
/// with VCVTNEPS2BF16 (amxAvailable() checks for it; the attribute lets a build with only the
/// AMX flags compile it), 16 values at a time.
__attribute__((target("avx512f,avx512bf16"))) inline void amxPackA(const float* A,
                                                                   Eigen::Index lda,
                                                                   Eigen::Index n, Eigen::Index k,
                                                                   Bf16* apack) {
  const Eigen::Index steps = (k + 31) / 32, tiles = (n + 31) / 32 * 2;
  for (Eigen::Index t = 0; t < tiles; ++t)
    for (int i = 0; i < 16; ++i) {
      const Eigen::Index row = t * 16 + i;
      const float* a = row < n ? A + row * lda : nullptr;
      for (Eigen::Index s = 0; s < steps; ++s) {
        Bf16* hi = apack + (t * steps + s) * 1024 + i * 32;
        Bf16* lo = hi + 512;
        const Eigen::Index c0 = s * 32;
        const int w = a ? static_cast<int>(std::min<Eigen::Index>(32, k - c0)) : 0;
        int c = 0;
        for (; c + 16 <= w; c += 16) {
          const __m512 x = _mm512_loadu_ps(a + c0 + c);
          const __m256i h = (__m256i)_mm512_cvtneps_pbh(x);
          const __m512 hf = _mm512_castsi512_ps(_mm512_slli_epi32(_mm512_cvtepu16_epi32(h), 16));
          const __m256i l = (__m256i)_mm512_cvtneps_pbh(_mm512_sub_ps(x, hf));
          _mm256_storeu_si256(reinterpret_cast<__m256i*>(hi + c), h);
          _mm256_storeu_si256(reinterpret_cast<__m256i*>(lo + c), l);
        }
        for (; c < w; ++c) bf16Split(a[c0 + c], hi + c, lo + c);
        for (; c < 32; ++c) hi[c] = lo[c] = 0;
      }
    }
}

// Stores C tile `idx` (rows r0.., columns j0..) into C, or through `edge` where it passes row n
// or column m. (Tile numbers must be literals for GCC's asm intrinsics, hence a macro.)
#define HAWOR_AMX_STORE_TILE(idx, r0, j0)                                                \
  do {                                                                                   \
    const Eigen::Index r0_ = (r0), j0_ = (j0);                                           \
    if (r0_ + 16 <= n && j0_ + 16 <= m) {                                                \
      _tile_stored(idx, C + r0_ * ldc + j0_, ldc * static_cast<Eigen::Index>(sizeof(float))); \
    } else if (r0_ < n && j0_ < m) {                                                     \
      compilerBarrier();                                                                 \
      _tile_stored(idx, edge, 64);                                                       \
      compilerBarrier();                                                                 \
      const Eigen::Index rows_ = std::min<Eigen::Index>(16, n - r0_);                    \
      const Eigen::Index cols_ = std::min<Eigen::Index>(16, m - j0_);                    \
      for (Eigen::Index i_ = 0; i_ < rows_; ++i_)                                        \
        for (Eigen::Index c_ = 0; c_ < cols_; ++c_)                                      \
          C[(r0_ + i_) * ldc + j0_ + c_] = edge[i_ * 16 + c_];                           \
      compilerBarrier();                                                                 \
    }                                                                                    \
  } while (0)

/// One k step's products into the 32×32 block of C (tiles 0–3): the two row tiles of A in tiles
/// 4–5 times the two panels of B in 6–7, whichever bf16 part (hi or lo) those tiles hold now.
/// (Fixed tile numbers: GCC's asm intrinsics need literals, so no parameters.)
__attribute__((always_inline)) inline void amxProducts2x2() {
  _tile_dpbf16ps(0, 4, 6);
  _tile_dpbf16ps(1, 4, 7);
  _tile_dpbf16ps(2, 5, 6);
  _tile_dpbf16ps(3, 5, 7);
}

/// C(n×m) = A·B (+ bias): bf16x3 (Split) or plain bf16 products, fp32 accumulation in tiles.
/// Tiles 0–3 hold a 32×32 block of C (2 row tiles × 2 panels), 4–5 two row tiles of A (hi, then
/// lo), 6–7 two panels of B (lo, then hi): per k step 6 tile loads for 12 products in the order
/// A_hi·B_lo, A_hi·B_hi, A_lo·B_hi. B's panel pair stays in cache while every row pair of A
/// runs over it, so the weights come from memory once per product.
template <bool Split>
void matmulAmxKernel(const float* A, Eigen::Index lda, Eigen::Index n, const AmxPanels& B,
                     float* C, Eigen::Index ldc, const float* bias, Bf16* apack) {
  const Eigen::Index k = B.rows(), m = B.cols(), steps = B.kSteps();
  if (n <= 0 || m <= 0) return;
  amxPackA(A, lda, n, k, apack);
  AmxTileConfig cfg;
  for (int i = 0; i < 8; ++i) {
    cfg.colsb[i] = 64;
    cfg.rows[i] = 16;
  }
  alignas(64) float biasTile[2][256];
  alignas(64) float edge[256];
  const Eigen::Index rowPairs = (n + 31) / 32;
  compilerBarrier();
  _tile_loadconfig(&cfg);
  for (Eigen::Index q = 0; q < B.panelPairs(); ++q) {
    compilerBarrier();
    for (int p = 0; p < 2; ++p)
      for (int c = 0; c < 16; ++c) {
        const Eigen::Index j = (2 * q + p) * 16 + c;
        const float v = bias && j < m ? bias[j] : 0.0f;
        for (int r = 0; r < 16; ++r) biasTile[p][r * 16 + c] = v;
      }
    compilerBarrier();
    for (Eigen::Index u = 0; u < rowPairs; ++u) {
      _tile_loadd(0, biasTile[0], 64);
      _tile_loadd(1, biasTile[1], 64);
      _tile_loadd(2, biasTile[0], 64);
      _tile_loadd(3, biasTile[1], 64);
      const Bf16* a0 = apack + (2 * u) * steps * 1024;
      const Bf16* a1 = a0 + steps * 1024;
      const std::uint16_t* b = B.block(q, 0);
      // (Software prefetch of the next panel pair into L2 was tried: no change in CPU time,
      // the hardware prefetchers already follow this order.)
      for (Eigen::Index s = 0; s < steps; ++s, a0 += 1024, a1 += 1024, b += 2048) {
        _tile_loadd(4, a0, 64);
        _tile_loadd(5, a1, 64);
        if (Split) {
          _tile_loadd(6, b + 512, 64);
          _tile_loadd(7, b + 1536, 64);
          amxProducts2x2();  // A_hi·B_lo
        }
        _tile_loadd(6, b, 64);
        _tile_loadd(7, b + 1024, 64);
        amxProducts2x2();  // A_hi·B_hi (plain bf16: the only one)
        if (Split) {
          _tile_loadd(4, a0 + 512, 64);
          _tile_loadd(5, a1 + 512, 64);
          amxProducts2x2();  // A_lo·B_hi
        }
      }
      const Eigen::Index r0 = 2 * u * 16, j0 = 2 * q * 16;
      HAWOR_AMX_STORE_TILE(0, r0, j0);
      HAWOR_AMX_STORE_TILE(1, r0, j0 + 16);
      HAWOR_AMX_STORE_TILE(2, r0 + 16, j0);
      HAWOR_AMX_STORE_TILE(3, r0 + 16, j0 + 16);
    }
  }
  _tile_release();
  compilerBarrier();
}

#undef HAWOR_AMX_STORE_TILE

}  // namespace detail

/// C(n×m) = A(n×k)·B (+ bias, m values, when not null) with AMX tiles: the bf16x3 split
/// (`split`, ~fp32 accuracy) or plain bf16. A and C row-major with leading dimensions lda, ldc;
/// `scratch` holds amxScratchSize(n, k) floats. Throws hawor::Error where !amxAvailable() (a
/// tile instruction would fault there).
inline void matmulAmx(const float* A, Eigen::Index lda, Eigen::Index n, const AmxPanels& B,
                      float* C, Eigen::Index ldc, const float* bias, float* scratch,
                      bool split = true) {
  if (!amxAvailable()) throw Error("matmulAmx: AMX tiles are not available here");
  detail::Bf16* apack = reinterpret_cast<detail::Bf16*>(scratch);
  if (split) {
    detail::matmulAmxKernel<true>(A, lda, n, B, C, ldc, bias, apack);
  } else {
    detail::matmulAmxKernel<false>(A, lda, n, B, C, ldc, bias, apack);
  }
}
#endif  // HAWOR_HAS_AMX

/// A fully connected layer y = x·Wᵀ + b (PyTorch nn.Linear, W out×in), applied to every row of
/// a row-major activation block. Holds W in the form its backend wants: as given (Eigen),
/// packed as Wᵀ (Packed), or Wᵀ split and packed for AMX tiles (Amx, AmxBf16), never two.
template <typename Scalar>
class Linear {
 public:
  Linear() = default;

  /// `weight` out×in; `bias` of length out, or empty for no bias. The backend runs as
  /// resolveMatmulBackend<Scalar>(backend) says (backend() tells which).
  Linear(const RowMatrixX<Scalar>& weight, const VecX<Scalar>& bias, MatmulBackend backend)
      : backend_(resolveMatmulBackend<Scalar>(backend)),
        in_(weight.cols()),
        out_(weight.rows()),
        bias_(bias) {
    if (bias.size() != 0 && bias.size() != weight.rows())
      throw Error("Linear: bias has " + std::to_string(bias.size()) + " values for " +
                  std::to_string(weight.rows()) + " outputs");
    if (backend_ == MatmulBackend::Eigen) {
      weight_ = weight;
    } else if (backend_ == MatmulBackend::Packed) {
      packed_.pack(weight.data(), 1, weight.cols(), weight.cols(), weight.rows());  // Wᵀ
    } else if constexpr (std::is_same<Scalar, float>::value) {
      amx_.pack(weight.data(), 1, weight.cols(), weight.cols(), weight.rows());  // Wᵀ
    }
  }

  Eigen::Index inDim() const { return in_; }
  Eigen::Index outDim() const { return out_; }
  MatmulBackend backend() const { return backend_; }

  /// Y = X·Wᵀ + b for the n rows of X (n×in) into Y (n×out): row-major blocks with unit inner
  /// stride (e.g. topRows / middleCols of a RowMatrixX). `scratch` holds matmulScratchSize(n,
  /// in) values (packedScratchSize for Packed; unused by the Eigen backend).
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
      const Scalar* bias = bias_.size() != 0 ? bias_.data() : nullptr;
#if defined(HAWOR_HAS_AMX)
      if constexpr (std::is_same<Scalar, float>::value) {
        if (backend_ == MatmulBackend::Amx || backend_ == MatmulBackend::AmxBf16) {
          matmulAmx(X.derived().data(), X.derived().outerStride(), X.rows(), amx_,
                    Y.derived().data(), Y.derived().outerStride(), bias, scratch,
                    backend_ == MatmulBackend::Amx);
          return;
        }
      }
#endif
      matmulPacked(X.derived().data(), X.derived().outerStride(), X.rows(), packed_,
                   Y.derived().data(), Y.derived().outerStride(), bias, scratch);
    }
  }

 private:
  MatmulBackend backend_ = MatmulBackend::Eigen;
  Eigen::Index in_ = 0, out_ = 0;
  RowMatrixX<Scalar> weight_;
  VecX<Scalar> bias_;
  PackedPanels<Scalar> packed_;
  AmxPanels amx_;  // float only
};

}  // namespace hawor
