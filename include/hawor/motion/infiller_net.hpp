// hawor/motion/infiller_net.hpp — the original HaWoR infiller network (docs/design.md §7), forward pass
// only, for weights converted from the official checkpoint (infiller_weights.hpp; none ship).
//
// One window of T ≤ W (= 120) frames, x (T × F), F = 218 = two hands × 109 features, and a
// per-frame validity v_t ∈ {0, 1} (official: 1 when both hands were observed at t; padded frames
// count as observed). With D = 384, H = 2048, 8 heads, LN = LayerNorm (eps 1e-5, biased
// variance, per-frame over the D features), all products per frame row:
//   h = [x | v]·W_inᵀ + b_in + PE                                   (T × D)
//   PE(t, 2i) = sin(t·ω_i), PE(t, 2i+1) = cos(t·ω_i), ω_i = 10000^(−2i/D)   (official table;
//       a pos_embedding.pe tensor in the weights file replaces the formula)
//   stage 1, 8 masked-attention blocks (the official MultiHeadedAttention + FeedForward):
//     n = LN_a(h);  h = n + MHA_mask(n)·W_oᵀ          residual from the *normalised* input:
//                                                     the official block does exactly this
//     h = h + ReLU(LN_f(h)·W_1ᵀ + b_1)·W_2ᵀ + b_2      pre-LN feed-forward, width H, ReLU
//   MHA_mask: per head, q/k/v = n·W_{q,k,v}ᵀ (no biases), a_tj = softmax_j(q_t·k_j / √D) over
//     the keys j with v_j = 1 only (invalid keys weigh exactly 0; every query, valid or not,
//     attends); note the 1/√D (not 1/√(D/heads)) scaling, as officially.
//   h = LN(h)                                              after stage 1
//   stage 2, 8 × PyTorch nn.TransformerEncoderLayer(D, 8, H, activation="gelu") in eval mode:
//     post-LN, no mask (the official forward passes none), scaling 1/√(D/heads),
//     h = LN_1(h + MHA(h));  h = LN_2(h + GELU(h·W_1ᵀ + b_1)·W_2ᵀ + b_2),
//     GELU(x) = x/2·(1 + erf(x/√2)) (the exact form, PyTorch's default)
//   y = h·W_decᵀ + b_dec                                   (T × F)
// Dropout is off (eval). The caller keeps y only at frames to fill (official: invalid frames).
// Every step is the official one read from the authors' model code (docs/design.md §7, *official*);
// the points docs/design.md §7 leaves open (the normalised residual, ReLU and width H in stage 1, no mask
// in stage 2, the PE table) follow it, so that converted weights reproduce its output.
//
// Cost: ≈ 8.7 GFLOP per 120-frame window (the feed-forwards are 70 %). Natively Eigen's GEMM
// carries it, or AMX tiles (bf16x3, matmul.hpp) for float in builds with AMX on CPUs that have
// it (the layers' products; attention stays with Eigen); in WebAssembly the packed kernel.
// Memory: the weights (34.8 M values: 139 MB in float, twice in double; AMX's bf16 hi + lo as
// much as float) and a workspace of 0.85 M values (3.4 MB in float).
// Thread-safety: forward() is const; concurrent calls need one InfillerWorkspace each. One call
// may itself run on several threads (a ThreadPool: the window's frames split between them).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <limits>
#include <string>
#include <unsupported/Eigen/SpecialFunctions>  // Array::erf (GELU)
#include <vector>

#include "hawor/common.hpp"
#include "hawor/motion/infiller_weights.hpp"
#include "hawor/matmul.hpp"
#include "hawor/motion/sequence.hpp"
#include "hawor/parallel.hpp"

namespace hawor {

/// The sinusoidal positional table (length × dModel): column 2i = sin(t·ω_i), column 2i+1 =
/// cos(t·ω_i), ω_i = exp(−2i·ln(10000)/dModel) (the official SinPositionalEncoding), computed in
/// double and rounded once to Scalar.
template <typename Scalar>
RowMatrixX<Scalar> sinusoidalPositionalEncoding(int length, int dModel) {
  RowMatrixX<Scalar> pe(length, dModel);
  for (int c = 0; c < dModel; ++c) {
    const double omega = std::exp(-double(c - c % 2) * std::log(10000.0) / double(dModel));
    for (int t = 0; t < length; ++t)
      pe(t, c) = static_cast<Scalar>(c % 2 == 0 ? std::sin(t * omega) : std::cos(t * omega));
  }
  return pe;
}

/// Pre-allocated buffers of one forward pass (rows sized for the full window W), so that
/// forward() allocates nothing of its own. `threads` = the most threads one forward may use
/// (the size of the ThreadPool passed to it): each has its own attention and packing buffers.
/// One workspace per concurrent forward().
template <typename Scalar>
struct InfillerWorkspace {
  explicit InfillerWorkspace(const InfillerConfig& c, int threads = 1) {
    c.validate();
    const Eigen::Index W = c.window, D = c.dModel;
    input.resize(W, c.inputDim());
    h.resize(W, D);
    n.resize(W, D);
    for (auto& q : qkv) q.resize(W, 3 * D);
    ctx.resize(W, D);
    tmp.resize(W, D);
    ff.resize(W, c.ffDim);
    keyMask.resize(W);
    const Eigen::Index maxK =
        std::max<Eigen::Index>({W, Eigen::Index(c.inputDim()), D, Eigen::Index(c.ffDim)});
    part.resize(static_cast<size_t>(std::max(1, threads)));
    for (Part& p : part) {
      p.scores.resize(W, W);
      p.scratch.resize(static_cast<size_t>(matmulScratchSize(W, maxK)));
      p.keys.reserve(c.headDim(), W);
      p.values.reserve(W, c.headDim());
    }
  }

  /// Buffers of one thread.
  struct Part {
    RowMatrixX<Scalar> scores;         // its query rows × the window's keys
    std::vector<Scalar> scratch;       // A packing of the packed and AMX backends
    PackedPanels<Scalar> keys, values; // one head's Kᵀ and V (packed backend)
  };

  RowMatrixX<Scalar> input, h, n, ctx, tmp, ff;
  RowMatrixX<Scalar> qkv[2];  // q | k | v of layer l in qkv[l % 2] (threads read all of one
                              // while they write their rows of the other)
  Eigen::Array<Scalar, 1, Eigen::Dynamic> keyMask;  // 1 = key may be attended, 0 = masked
  std::vector<Part> part;                           // one per thread
};

/// The infiller network with its weights, ready to run (see the file comment for the maths).
template <typename Scalar>
class InfillerNet {
 public:
  /// Takes the weights (sizes and finiteness checked again: they may have been built in code)
  /// and lays them out for `backend`, as resolveMatmulBackend<Scalar> resolves it (Auto: AMX
  /// tiles, bf16x3, for float where the build and the CPU have them; else Eigen natively, the
  /// packed kernel in WebAssembly). backend() tells which runs.
  explicit InfillerNet(const InfillerWeights<Scalar>& w,
                       MatmulBackend backend = MatmulBackend::Auto)
      : config_(w.config), backend_(resolveMatmulBackend<Scalar>(backend)) {
    checkInfillerWeights(w);
    const int D = config_.dModel;
    const VecX<Scalar> none;
    backend = backend_;
    input_ = Linear<Scalar>(w.inputWeight, w.inputBias, backend);
    positional_ = w.positional.size() != 0
                      ? w.positional
                      : sinusoidalPositionalEncoding<Scalar>(config_.window, D);
    for (const auto& b : w.maskedBlocks) {
      Masked m;
      RowMatrixX<Scalar> qkv(3 * D, D);
      qkv << b.q, b.k, b.v;
      m.qkv = Linear<Scalar>(qkv, none, backend);
      m.out = Linear<Scalar>(b.out, none, backend);
      m.ff1 = Linear<Scalar>(b.ff1Weight, b.ff1Bias, backend);
      m.ff2 = Linear<Scalar>(b.ff2Weight, b.ff2Bias, backend);
      m.attnNormWeight = b.attnNormWeight;
      m.attnNormBias = b.attnNormBias;
      m.ffNormWeight = b.ffNormWeight;
      m.ffNormBias = b.ffNormBias;
      masked_.push_back(std::move(m));
    }
    normWeight_ = w.normWeight;
    normBias_ = w.normBias;
    for (const auto& e : w.encoderLayers) {
      Encoder l;
      l.qkv = Linear<Scalar>(e.inProjWeight, e.inProjBias, backend);
      l.out = Linear<Scalar>(e.outProjWeight, e.outProjBias, backend);
      l.ff1 = Linear<Scalar>(e.linear1Weight, e.linear1Bias, backend);
      l.ff2 = Linear<Scalar>(e.linear2Weight, e.linear2Bias, backend);
      l.norm1Weight = e.norm1Weight;
      l.norm1Bias = e.norm1Bias;
      l.norm2Weight = e.norm2Weight;
      l.norm2Bias = e.norm2Bias;
      encoder_.push_back(std::move(l));
    }
    decoder_ = Linear<Scalar>(w.decoderWeight, w.decoderBias, backend);
  }

  /// Reads the weights file (infiller_weights.hpp) and builds the network.
  static InfillerNet read(const std::string& path, const InfillerConfig& config = {},
                          MatmulBackend backend = MatmulBackend::Auto) {
    return InfillerNet(readInfillerWeights<Scalar>(path, config), backend);
  }

  const InfillerConfig& config() const { return config_; }
  MatmulBackend backend() const { return backend_; }
  /// The positional table in use (W × D).
  const RowMatrixX<Scalar>& positionalTable() const { return positional_; }

  /// y (T × F) for the window x (T × F, 1 ≤ T ≤ W) with per-frame validity `valid` (T entries,
  /// nonzero = observed). `y` is resized to T × F when it is not already (no other allocation
  /// happens here, Eigen's GEMM blocking buffers aside). With a pool, the frames (rows) are split
  /// between min(pool size, workspace threads) threads: every step but attention is per row, and
  /// attention reads the keys and values of all rows, so one fork–join per layer suffices. The
  /// result equals the one-thread result up to rounding. Throws hawor::Error for wrong sizes, a
  /// non-finite input, or (with masked blocks) a window without any valid frame, where every
  /// attention key would be masked (the official model returns NaN there).
  void forward(const Eigen::Ref<const RowMatrixX<Scalar>>& x, const ValidMask& valid,
               RowMatrixX<Scalar>& y, InfillerWorkspace<Scalar>& ws,
               ThreadPool* pool = nullptr) const {
    const Eigen::Index T = x.rows(), F = config_.features, D = config_.dModel;
    if (T < 1 || T > config_.window || x.cols() != F)
      throw Error("InfillerNet: input is " + std::to_string(T) + "x" + std::to_string(x.cols()) +
                  ", expected T x " + std::to_string(F) +
                  " with 1 <= T <= " + std::to_string(config_.window));
    checkMask(valid, T, "InfillerNet");
    if (ws.h.rows() != config_.window || ws.h.cols() != D || ws.ff.cols() != config_.ffDim ||
        ws.input.cols() != config_.inputDim() || ws.part.empty())
      throw Error("InfillerNet: workspace was made for another configuration");
    for (Eigen::Index t = 0; t < T; ++t)
      if (!x.row(t).allFinite())
        throw Error("InfillerNet: non-finite input at frame " + std::to_string(t));
    if (!masked_.empty() && countValid(valid) == 0)
      throw Error("InfillerNet: no valid frame in the window: every attention key is masked");
    if (y.rows() != T || y.cols() != F) y.resize(T, F);

    for (Eigen::Index t = 0; t < T; ++t) {
      const bool v = valid[static_cast<size_t>(t)] != 0;
      ws.input.row(t).head(F) = x.row(t);
      ws.input(t, F) = v ? Scalar(1) : Scalar(0);
      ws.keyMask(t) = v ? Scalar(1) : Scalar(0);
    }
    // Row ranges: whole tiles of the packed kernel (kPackedMR rows), as even as possible.
    const Eigen::Index tiles = (T + kPackedMR - 1) / kPackedMR;
    int parts = pool ? std::min<int>(pool->size(), static_cast<int>(ws.part.size())) : 1;
    parts = static_cast<int>(std::min<Eigen::Index>(parts, tiles));
    const int layers = static_cast<int>(masked_.size() + encoder_.size());
    for (int phase = 0; phase <= layers; ++phase) {
      const auto task = [&](int p) {
        const Eigen::Index r0 = std::min(T, tiles * p / parts * kPackedMR);
        const Eigen::Index r1 = std::min(T, tiles * (p + 1) / parts * kPackedMR);
        if (r1 > r0) rowsPhase(phase, r0, r1 - r0, T, y, ws, ws.part[static_cast<size_t>(p)]);
      };
      if (parts > 1) {
        pool->run(parts, task);
      } else {
        task(0);
      }
    }
  }

  /// forward() with its own workspace and output (allocates; for one-off calls).
  RowMatrixX<Scalar> forward(const Eigen::Ref<const RowMatrixX<Scalar>>& x,
                             const ValidMask& valid, ThreadPool* pool = nullptr) const {
    InfillerWorkspace<Scalar> ws(config_, pool ? pool->size() : 1);
    RowMatrixX<Scalar> y;
    forward(x, valid, y, ws, pool);
    return y;
  }

 private:
  struct Masked {
    Linear<Scalar> qkv, out, ff1, ff2;
    VecX<Scalar> attnNormWeight, attnNormBias, ffNormWeight, ffNormBias;
  };
  struct Encoder {
    Linear<Scalar> qkv, out, ff1, ff2;
    VecX<Scalar> norm1Weight, norm1Bias, norm2Weight, norm2Bias;
  };

  /// Y = LN(X)·γ + β per row: (x − mean)/√(var + 1e-5), var biased (PyTorch's LayerNorm).
  /// X and Y may be the same block.
  template <typename XB, typename YB>
  static void layerNorm(const XB& X, const VecX<Scalar>& gamma, const VecX<Scalar>& beta, YB&& Y) {
    const Scalar eps = Scalar(1e-5);
    const Scalar invD = Scalar(1) / Scalar(X.cols());
    for (Eigen::Index t = 0; t < X.rows(); ++t) {
      const Scalar mean = X.row(t).sum() * invD;
      const Scalar var = (X.row(t).array() - mean).square().sum() * invD;
      const Scalar inv = Scalar(1) / std::sqrt(var + eps);
      Y.row(t) =
          ((X.row(t).array() - mean) * inv * gamma.transpose().array() + beta.transpose().array())
              .matrix();
    }
  }

  /// GELU, exact form x/2·(1 + erf(x/√2)), in place. Eigen's erf: for float a vectorised
  /// rational approximation (|error| < 5e-7, ~25x faster than std::erf, which would be a third
  /// of the float forward pass), for double std::erf.
  template <typename B>
  static void gelu(B&& X) {
    const Scalar invSqrt2 = Scalar(0.70710678118654752440);
    auto a = X.array();
    a = Scalar(0.5) * a * (Scalar(1) + (a * invSqrt2).erf());
  }

  /// Phase `phase` of the forward pass for the rows [r0, r0 + R) of a T-frame window: the
  /// input layer (phase 0) or the rest of layer phase − 1 from its attention on (which reads
  /// every row's keys and values of that layer), then the start of layer `phase` up to its q, k,
  /// v (or, after the last layer, the output layer into y).
  void rowsPhase(int phase, Eigen::Index r0, Eigen::Index R, Eigen::Index T, RowMatrixX<Scalar>& y,
                 InfillerWorkspace<Scalar>& ws, typename InfillerWorkspace<Scalar>::Part& part) const {
    const int M = static_cast<int>(masked_.size());
    const int layers = M + static_cast<int>(encoder_.size());
    auto h = ws.h.middleRows(r0, R);
    auto n = ws.n.middleRows(r0, R);
    auto tmp = ws.tmp.middleRows(r0, R);
    auto ff = ws.ff.middleRows(r0, R);
    auto ctx = ws.ctx.middleRows(r0, R);
    Scalar* scratch = part.scratch.data();
    if (phase == 0) {
      input_.apply(ws.input.middleRows(r0, R), h, scratch);
      h += positional_.middleRows(r0, R);
    } else if (phase - 1 < M) {
      // stage 1: the rest of a pre-LN masked attention block
      const Masked& m = masked_[static_cast<size_t>(phase - 1)];
      attention(ws.qkv[(phase - 1) % 2], r0, R, T, Scalar(1) / std::sqrt(Scalar(config_.dModel)),
                true, ws, part);
      m.out.apply(ctx, tmp, scratch);
      h = n + tmp;  // official: the residual adds the normalised input
      layerNorm(h, m.ffNormWeight, m.ffNormBias, n);
      m.ff1.apply(n, ff, scratch);
      ff = ff.cwiseMax(Scalar(0));
      m.ff2.apply(ff, tmp, scratch);
      h += tmp;
    } else {
      // stage 2: the rest of a post-LN encoder layer (GELU, no mask)
      const Encoder& e = encoder_[static_cast<size_t>(phase - 1 - M)];
      attention(ws.qkv[(phase - 1) % 2], r0, R, T,
                Scalar(1) / std::sqrt(Scalar(config_.headDim())), false, ws, part);
      e.out.apply(ctx, tmp, scratch);
      h += tmp;
      layerNorm(h, e.norm1Weight, e.norm1Bias, h);
      e.ff1.apply(h, ff, scratch);
      gelu(ff);
      e.ff2.apply(ff, tmp, scratch);
      h += tmp;
      layerNorm(h, e.norm2Weight, e.norm2Bias, h);
    }
    if (phase == M) layerNorm(h, normWeight_, normBias_, h);  // after stage 1
    if (phase == layers) {
      decoder_.apply(h, y.middleRows(r0, R), scratch);
    } else if (phase < M) {
      const Masked& m = masked_[static_cast<size_t>(phase)];
      layerNorm(h, m.attnNormWeight, m.attnNormBias, n);
      m.qkv.apply(n, ws.qkv[phase % 2].middleRows(r0, R), scratch);
    } else {
      encoder_[static_cast<size_t>(phase - M)].qkv.apply(h, ws.qkv[phase % 2].middleRows(r0, R),
                                                          scratch);
    }
  }

  /// Multi-head attention of the query rows [r0, r0 + R) over all T keys of `qkv` (T × 3D:
  /// q | k | v, heads contiguous within each) into those rows of ws.ctx (heads concatenated):
  /// ctx_h = softmax(q_h·k_hᵀ·scale)·v_h, the softmax over the keys allowed by ws.keyMask when
  /// `masked` (the others get weight exactly 0).
  void attention(const RowMatrixX<Scalar>& qkv, Eigen::Index r0, Eigen::Index R, Eigen::Index T,
                 Scalar scale, bool masked, InfillerWorkspace<Scalar>& ws,
                 typename InfillerWorkspace<Scalar>::Part& part) const {
    const Eigen::Index D = config_.dModel, dh = config_.headDim();
    auto S = part.scores.topLeftCorner(R, T);
    const auto mask = ws.keyMask.head(T);
    const Scalar lowest = std::numeric_limits<Scalar>::lowest();
    const Eigen::Index ld = qkv.cols(), ldc = ws.ctx.cols();
    for (int hd = 0; hd < config_.heads; ++hd) {
      const Eigen::Index c = hd * dh;
      if (backend_ != MatmulBackend::Packed) {  // Eigen; the AMX backend too (4 % of the work)
        S.noalias() = qkv.block(r0, c, R, dh) * qkv.block(0, D + c, T, dh).transpose();
      } else {
        part.keys.pack(qkv.data() + D + c, 1, ld, dh, T);  // k_hᵀ: dh × T
        matmulPacked(qkv.data() + r0 * ld + c, ld, R, part.keys, S.data(), S.outerStride(),
                     static_cast<const Scalar*>(nullptr), part.scratch.data());
      }
      for (Eigen::Index t = 0; t < R; ++t) {
        auto r = S.row(t).array();
        r *= scale;
        if (masked) r = (mask > Scalar(0)).select(r, lowest);
        const Scalar mx = r.maxCoeff();
        r = (r - mx).exp();
        if (masked) r *= mask;
        r /= r.sum();
      }
      if (backend_ != MatmulBackend::Packed) {
        ws.ctx.block(r0, c, R, dh).noalias() = S * qkv.block(0, 2 * D + c, T, dh);
      } else {
        part.values.pack(qkv.data() + 2 * D + c, ld, 1, T, dh);  // v_h: T × dh
        matmulPacked(S.data(), S.outerStride(), R, part.values, ws.ctx.data() + r0 * ldc + c, ldc,
                     static_cast<const Scalar*>(nullptr), part.scratch.data());
      }
    }
  }

  InfillerConfig config_;
  MatmulBackend backend_;
  Linear<Scalar> input_, decoder_;
  RowMatrixX<Scalar> positional_;
  std::vector<Masked> masked_;
  VecX<Scalar> normWeight_, normBias_;
  std::vector<Encoder> encoder_;
};

}  // namespace hawor
