// hawor/motion/infiller_weights.hpp — the infiller network's sizes and weights, read from an
// .npz of named tensors (docs/design.md §7; the network itself is infiller_net.hpp).
//
// Tensor names are exactly the keys of the official checkpoint's state_dict
// (ckpt["transformer_encoder_state_dict"] of the original `TransformerModel(seq_len=120,
// input_dim=218, d_model=384, nhead=8, d_hid=2048, nlayers=8, masked_attention_stage=True)`), so
// a user who owns that checkpoint converts it with one line of numpy, and a converter is never
// needed to rename anything:
//   np.savez("infiller.npz", **{k: v.float().numpy() for k, v in sd.items()})
// Shapes, with F = features (218), D = dModel (384), H = ffDim (2048), W = window (120),
// i < maskedLayers (8), l < encoderLayers (8); every tensor is required unless marked optional:
//   input_layer.weight                      (D, F+1)   frame features + validity channel -> D
//   input_layer.bias                        (D)
//   pos_embedding.pe                        (W, 1, D) or (W, D), optional: the sinusoidal table;
//                                           when absent it is computed (infiller_net.hpp)
//   att_layers.i.layer_norm.{weight,bias}   (D)        pre-LayerNorm of masked attention block i
//   att_layers.i.{q,k,v}_linear.weight      (D, D)     no biases (bias=False officially)
//   att_layers.i.out_linear.weight          (D, D)
//   pff_layers.i.layer_norm.{weight,bias}   (D)        pre-LayerNorm of its feed-forward
//   pff_layers.i.network.0.{weight,bias}    (H, D), (H)
//   pff_layers.i.network.3.{weight,bias}    (D, H), (D)
//   layer_norm.{weight,bias}                (D)        after the masked blocks
//   transformer_encoder.layers.l.self_attn.in_proj_weight   (3D, D)  rows: q, k, v
//   transformer_encoder.layers.l.self_attn.in_proj_bias     (3D)
//   transformer_encoder.layers.l.self_attn.out_proj.{weight,bias}  (D, D), (D)
//   transformer_encoder.layers.l.linear1.{weight,bias}      (H, D), (H)
//   transformer_encoder.layers.l.linear2.{weight,bias}      (D, H), (D)
//   transformer_encoder.layers.l.norm1.{weight,bias}        (D)
//   transformer_encoder.layers.l.norm2.{weight,bias}        (D)
//   decoder.{weight,bias}                   (F, D), (F)
// Linear weights are (out, in) as in PyTorch. Any floating dtype (float16/32/64, either byte
// order) is accepted and converted to Scalar. A missing tensor, a wrong shape, a non-floating
// dtype, a non-finite value or a key that is not in this list (e.g. the layers of a deeper
// model) is a hawor::Error naming the file and the tensor.
#pragma once

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/io/npz.hpp"
#include "hawor/matmul.hpp"

namespace hawor {

/// Sizes of the infiller network. The defaults are the official model's (docs/design.md §7); smaller
/// ones serve tests.
struct InfillerConfig {
  int window = 120;       ///< frames per window W (length of the positional table)
  int features = 218;     ///< per-frame features F of both hands (2 × 109), also the output size
  int dModel = 384;       ///< model width D
  int heads = 8;          ///< attention heads of both stages (D divisible by heads)
  int ffDim = 2048;       ///< feed-forward width H of both stages (official d_hid)
  int maskedLayers = 8;   ///< pre-LayerNorm masked-attention blocks (+ their feed-forwards)
  int encoderLayers = 8;  ///< nn.TransformerEncoderLayer blocks (post-LN, GELU)

  /// Throws hawor::Error for non-positive sizes or dModel not divisible by heads.
  void validate() const {
    const auto positive = [](int v, const char* name) {
      if (v <= 0)
        throw Error("InfillerConfig: " + std::string(name) + " must be positive, got " +
                    std::to_string(v));
    };
    positive(window, "window");
    positive(features, "features");
    positive(dModel, "dModel");
    positive(heads, "heads");
    positive(ffDim, "ffDim");
    if (maskedLayers < 0 || encoderLayers < 0)
      throw Error("InfillerConfig: layer counts must not be negative");
    if (dModel % heads != 0)
      throw Error("InfillerConfig: dModel " + std::to_string(dModel) + " is not divisible by " +
                  std::to_string(heads) + " heads");
  }

  int headDim() const { return dModel / heads; }
  int inputDim() const { return features + 1; }
};

/// Weights of one pre-LayerNorm masked-attention block and its feed-forward (stage 1).
template <typename Scalar>
struct InfillerMaskedBlock {
  VecX<Scalar> attnNormWeight, attnNormBias;  // att_layers.i.layer_norm
  RowMatrixX<Scalar> q, k, v, out;            // att_layers.i.{q,k,v,out}_linear.weight (D×D)
  VecX<Scalar> ffNormWeight, ffNormBias;      // pff_layers.i.layer_norm
  RowMatrixX<Scalar> ff1Weight, ff2Weight;    // pff_layers.i.network.{0,3}.weight
  VecX<Scalar> ff1Bias, ff2Bias;
};

/// Weights of one nn.TransformerEncoderLayer (stage 2).
template <typename Scalar>
struct InfillerEncoderLayer {
  RowMatrixX<Scalar> inProjWeight, outProjWeight, linear1Weight, linear2Weight;
  VecX<Scalar> inProjBias, outProjBias, linear1Bias, linear2Bias;
  VecX<Scalar> norm1Weight, norm1Bias, norm2Weight, norm2Bias;
};

/// Every tensor of the network, in PyTorch's layouts (see the file comment for the names).
template <typename Scalar>
struct InfillerWeights {
  InfillerConfig config;
  RowMatrixX<Scalar> inputWeight;  // D × (F+1)
  VecX<Scalar> inputBias;
  RowMatrixX<Scalar> positional;  // W × D, or empty: computed from the formula
  std::vector<InfillerMaskedBlock<Scalar>> maskedBlocks;
  VecX<Scalar> normWeight, normBias;  // layer_norm after stage 1
  std::vector<InfillerEncoderLayer<Scalar>> encoderLayers;
  RowMatrixX<Scalar> decoderWeight;  // F × D
  VecX<Scalar> decoderBias;
};

/// One tensor of the file format: its name and shape (the positional table's alternative
/// (W, D) shape is also accepted).
struct InfillerTensorSpec {
  std::string name;
  std::vector<size_t> shape;
  bool optional = false;
};

/// The full list of tensors for `config`, in state_dict order (the format's documentation
/// in code: the loader, the tests and the ONNX generator's names follow it).
inline std::vector<InfillerTensorSpec> infillerTensorSpecs(const InfillerConfig& config) {
  config.validate();
  const size_t F = static_cast<size_t>(config.features), D = static_cast<size_t>(config.dModel),
               H = static_cast<size_t>(config.ffDim), W = static_cast<size_t>(config.window);
  std::vector<InfillerTensorSpec> s;
  s.push_back({"pos_embedding.pe", {W, 1, D}, true});
  s.push_back({"input_layer.weight", {D, F + 1}});
  s.push_back({"input_layer.bias", {D}});
  for (int i = 0; i < config.maskedLayers; ++i) {
    const std::string a = "att_layers." + std::to_string(i) + ".";
    s.push_back({a + "q_linear.weight", {D, D}});
    s.push_back({a + "k_linear.weight", {D, D}});
    s.push_back({a + "v_linear.weight", {D, D}});
    s.push_back({a + "out_linear.weight", {D, D}});
    s.push_back({a + "layer_norm.weight", {D}});
    s.push_back({a + "layer_norm.bias", {D}});
  }
  for (int i = 0; i < config.maskedLayers; ++i) {
    const std::string p = "pff_layers." + std::to_string(i) + ".";
    s.push_back({p + "layer_norm.weight", {D}});
    s.push_back({p + "layer_norm.bias", {D}});
    s.push_back({p + "network.0.weight", {H, D}});
    s.push_back({p + "network.0.bias", {H}});
    s.push_back({p + "network.3.weight", {D, H}});
    s.push_back({p + "network.3.bias", {D}});
  }
  s.push_back({"layer_norm.weight", {D}});
  s.push_back({"layer_norm.bias", {D}});
  for (int l = 0; l < config.encoderLayers; ++l) {
    const std::string e = "transformer_encoder.layers." + std::to_string(l) + ".";
    s.push_back({e + "self_attn.in_proj_weight", {3 * D, D}});
    s.push_back({e + "self_attn.in_proj_bias", {3 * D}});
    s.push_back({e + "self_attn.out_proj.weight", {D, D}});
    s.push_back({e + "self_attn.out_proj.bias", {D}});
    s.push_back({e + "linear1.weight", {H, D}});
    s.push_back({e + "linear1.bias", {H}});
    s.push_back({e + "linear2.weight", {D, H}});
    s.push_back({e + "linear2.bias", {D}});
    s.push_back({e + "norm1.weight", {D}});
    s.push_back({e + "norm1.bias", {D}});
    s.push_back({e + "norm2.weight", {D}});
    s.push_back({e + "norm2.bias", {D}});
  }
  s.push_back({"decoder.weight", {F, D}});
  s.push_back({"decoder.bias", {F}});
  return s;
}

namespace detail {

inline std::string infillerShapeText(const std::vector<size_t>& shape) {
  std::string t = "(";
  for (size_t i = 0; i < shape.size(); ++i) t += (i ? ", " : "") + std::to_string(shape[i]);
  return t + (shape.size() == 1 ? ",)" : ")");
}

/// Reads tensor `spec` from `npz` as a row-major matrix of its 2-D shape (rows × cols; a 1-D
/// tensor as a column), checking dtype, shape and finiteness. `alt` is another accepted shape.
template <typename Scalar>
RowMatrixX<Scalar> readInfillerTensor(const Npz& npz, const InfillerTensorSpec& spec,
                                      const std::vector<size_t>& alt = {}) {
  const std::string what = npz.source() + ": tensor '" + spec.name + "'";
  if (!npz.has(spec.name))
    throw Error(what + " is missing (expected shape " + infillerShapeText(spec.shape) + ")");
  const NpyArray& a = npz.get(spec.name);
  const NpyType t = a.type(what);
  if (t.kind != NpyKind::Float)
    throw Error(what + " has dtype " + t.name() + ": a floating dtype (float16/32/64) is required");
  if (a.shape != spec.shape && (alt.empty() || a.shape != alt))
    throw Error(what + " has shape " + infillerShapeText(a.shape) + ", expected " +
                infillerShapeText(spec.shape) +
                (alt.empty() ? std::string() : " or " + infillerShapeText(alt)));
  const std::vector<double> v = a.as<double>(what);
  for (size_t i = 0; i < v.size(); ++i) {
    if (!std::isfinite(v[i]))
      throw Error(what + " holds a non-finite value (" + std::to_string(v[i]) + ") at element " +
                  std::to_string(i));
  }
  const Eigen::Index rows = static_cast<Eigen::Index>(spec.shape[0]);
  const Eigen::Index cols = static_cast<Eigen::Index>(v.size()) / std::max<Eigen::Index>(rows, 1);
  RowMatrixX<Scalar> m(rows, cols);
  for (size_t i = 0; i < v.size(); ++i) m.data()[i] = static_cast<Scalar>(v[i]);
  if (!m.allFinite()) throw Error(what + " holds values beyond the range of float");
  return m;
}

/// Rows and columns a tensor of `shape` has in memory: (d0, d1·d2·…), a 1-D one a column.
inline std::pair<Eigen::Index, Eigen::Index> infillerMatrixSize(const std::vector<size_t>& shape) {
  size_t cols = 1;
  for (size_t i = 1; i < shape.size(); ++i) cols *= shape[i];
  return {static_cast<Eigen::Index>(shape.at(0)), static_cast<Eigen::Index>(cols)};
}

}  // namespace detail

/// Calls fn(spec, tensor) for every tensor of `w` (InfillerWeights, const or not) in the order
/// of infillerTensorSpecs: the one place that maps names onto fields. `tensor` is a RowMatrixX
/// (2-D tensors and the positional table) or a VecX (1-D). The positional table is visited when
/// it is present (non-empty) or `withPositional` is set. Throws if the layer counts are not the
/// configuration's.
template <typename Weights, typename Fn>
void forEachInfillerTensor(Weights& w, Fn&& fn, bool withPositional = false) {
  const std::vector<InfillerTensorSpec> specs = infillerTensorSpecs(w.config);
  if (w.maskedBlocks.size() != static_cast<size_t>(w.config.maskedLayers) ||
      w.encoderLayers.size() != static_cast<size_t>(w.config.encoderLayers))
    throw Error("InfillerWeights: " + std::to_string(w.maskedBlocks.size()) + " masked and " +
                std::to_string(w.encoderLayers.size()) + " encoder layers, the configuration has " +
                std::to_string(w.config.maskedLayers) + " and " +
                std::to_string(w.config.encoderLayers));
  size_t next = 0;
  const auto visit = [&](auto& t) { fn(specs.at(next++), t); };
  if (withPositional || w.positional.size() != 0) {
    visit(w.positional);
  } else {
    ++next;
  }
  visit(w.inputWeight);
  visit(w.inputBias);
  for (auto& b : w.maskedBlocks) {
    visit(b.q);
    visit(b.k);
    visit(b.v);
    visit(b.out);
    visit(b.attnNormWeight);
    visit(b.attnNormBias);
  }
  for (auto& b : w.maskedBlocks) {
    visit(b.ffNormWeight);
    visit(b.ffNormBias);
    visit(b.ff1Weight);
    visit(b.ff1Bias);
    visit(b.ff2Weight);
    visit(b.ff2Bias);
  }
  visit(w.normWeight);
  visit(w.normBias);
  for (auto& e : w.encoderLayers) {
    visit(e.inProjWeight);
    visit(e.inProjBias);
    visit(e.outProjWeight);
    visit(e.outProjBias);
    visit(e.linear1Weight);
    visit(e.linear1Bias);
    visit(e.linear2Weight);
    visit(e.linear2Bias);
    visit(e.norm1Weight);
    visit(e.norm1Bias);
    visit(e.norm2Weight);
    visit(e.norm2Bias);
  }
  visit(w.decoderWeight);
  visit(w.decoderBias);
}

/// Checks that every tensor of `w` has its configuration's size and finite values (weights
/// built in code rather than loaded). Throws hawor::Error naming the tensor.
template <typename Scalar>
void checkInfillerWeights(const InfillerWeights<Scalar>& w) {
  w.config.validate();
  forEachInfillerTensor(w, [](const InfillerTensorSpec& spec, const auto& t) {
    const auto size = detail::infillerMatrixSize(spec.shape);
    if (t.rows() != size.first || t.cols() != size.second)
      throw Error("InfillerWeights: '" + spec.name + "' is " + std::to_string(t.rows()) + "x" +
                  std::to_string(t.cols()) + ", expected " + std::to_string(size.first) + "x" +
                  std::to_string(size.second) + " (shape " + detail::infillerShapeText(spec.shape) +
                  ")");
    if (!t.allFinite())
      throw Error("InfillerWeights: '" + spec.name + "' holds a non-finite value");
  });
}

/// Reads and checks every tensor of the network for `config` from an .npz archive (names and
/// shapes in the file comment). Throws hawor::Error naming the archive and the tensor.
template <typename Scalar>
InfillerWeights<Scalar> loadInfillerWeights(const Npz& npz, const InfillerConfig& config = {}) {
  const std::vector<InfillerTensorSpec> specs = infillerTensorSpecs(config);
  // Unknown keys first: a checkpoint of another shape (more layers, no masked stage) says so
  // instead of loading half of itself.
  std::set<std::string> known;
  for (const auto& s : specs) known.insert(s.name);
  std::vector<std::string> unknown;
  for (const auto& name : npz.names())
    if (!known.count(name)) unknown.push_back(name);
  if (!unknown.empty()) {
    std::string list;
    for (size_t i = 0; i < unknown.size() && i < 8; ++i) list += (i ? ", " : "") + unknown[i];
    if (unknown.size() > 8) list += ", ...";
    throw Error(npz.source() + ": " + std::to_string(unknown.size()) +
                " tensor(s) not part of the infiller network with " +
                std::to_string(config.maskedLayers) + " masked and " +
                std::to_string(config.encoderLayers) + " encoder layers: " + list);
  }
  InfillerWeights<Scalar> w;
  w.config = config;
  w.maskedBlocks.resize(static_cast<size_t>(config.maskedLayers));
  w.encoderLayers.resize(static_cast<size_t>(config.encoderLayers));
  const bool withPositional = npz.has(specs.at(0).name);
  const std::vector<size_t> positionalAlt{static_cast<size_t>(config.window),
                                          static_cast<size_t>(config.dModel)};
  forEachInfillerTensor(
      w,
      [&](const InfillerTensorSpec& spec, auto& t) {
        // (rows, cols) of the shape; a 1-D tensor is one column, which a VecX takes as is
        t = detail::readInfillerTensor<Scalar>(
            npz, spec, spec.optional ? positionalAlt : std::vector<size_t>{});
      },
      withPositional);
  return w;
}

/// loadInfillerWeights from a file (np.savez or np.savez_compressed).
template <typename Scalar>
InfillerWeights<Scalar> readInfillerWeights(const std::string& path,
                                            const InfillerConfig& config = {}) {
  return loadInfillerWeights<Scalar>(Npz::read(path), config);
}

/// The weights as an .npz archive of float32 (or float64 with `asDouble`) tensors under the
/// names above: the inverse of loadInfillerWeights (tests, and tools that make weights).
template <typename Scalar>
Npz infillerWeightsToNpz(const InfillerWeights<Scalar>& w, bool asDouble = false) {
  checkInfillerWeights(w);
  Npz npz;
  forEachInfillerTensor(w, [&](const InfillerTensorSpec& spec, const auto& t) {
    if (asDouble) {
      std::vector<double> v(static_cast<size_t>(t.size()));
      for (Eigen::Index i = 0; i < t.size(); ++i) v[static_cast<size_t>(i)] = double(t.data()[i]);
      npz.set(spec.name, NpyArray::fromData(v.data(), spec.shape));
    } else {
      std::vector<float> v(static_cast<size_t>(t.size()));
      for (Eigen::Index i = 0; i < t.size(); ++i) v[static_cast<size_t>(i)] = float(t.data()[i]);
      npz.set(spec.name, NpyArray::fromData(v.data(), spec.shape));
    }
  });
  return npz;
}

}  // namespace hawor
