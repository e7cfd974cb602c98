// hawor/motion/transformer_infill.hpp — the original infiller network (infiller_net.hpp) as a
// window infiller of the two-hand pipeline (infill_window.hpp), i.e. the whole of the official
// infilling: canonical windows, LERP/SLERP pre-fill, the network, only missing frames replaced.
//
// Per window: x = the pre-filled canonical features [left | right] (W × 218 for MANO hands),
// cast to the network's scalar; the validity channel and the attention mask v_t = 1 where both
// hands were observed at frame t (official; padding repeats the last frame's flags). A window
// where no frame has both hands (one hand out of view throughout, which the official model
// cannot attend over: every key masked) uses the frames where either hand was observed instead,
// so that the network still sees the evidence; a window with no observed frame at all is left to
// the pre-fill. The pipeline then takes the output only at each hand's missing frames.
// Thread-safety: infillWindow() is const and allocates its own workspace; the optional pool is
// used by one call at a time.
#pragma once

#include <string>

#include "hawor/common.hpp"
#include "hawor/motion/infill_window.hpp"
#include "hawor/motion/infiller_net.hpp"
#include "hawor/parallel.hpp"

namespace hawor {

/// The network as a WindowInfiller. Scalar: the pipeline's; NetScalar: the network's (float
/// halves the weights' memory and runs about twice as fast as double; see the README).
template <typename Scalar, typename NetScalar = Scalar>
class TransformerWindowInfiller : public WindowInfiller<Scalar> {
 public:
  /// `net` must outlive this object. `pool` (optional, may be null) runs each window's forward
  /// pass on several threads.
  explicit TransformerWindowInfiller(const InfillerNet<NetScalar>& net, ThreadPool* pool = nullptr)
      : net_(net), pool_(pool) {}

  /// The hands' feature layout the network was built for: 2·layout.size() must equal its
  /// feature count (MANO: 15 joint rotations, 10 betas → 2 × 109 = 218).
  void checkLayout(const HandFeatureLayout& l) const {
    if (2 * l.size() != net_.config().features)
      throw Error("transformer infiller: the hands have " + std::to_string(l.joints) +
                  " joint rotations and " + std::to_string(l.betas) + " betas (" +
                  std::to_string(2 * l.size()) + " features per frame), the network expects " +
                  std::to_string(net_.config().features) +
                  " (MANO hands: 15 joint rotations, 10 betas)");
  }

  Sequence<Scalar> infillWindow(const InfillWindow<Scalar>& w) const override {
    checkLayout(w.layout);
    const Eigen::Index W = w.features.rows();
    if (W != net_.config().window)
      throw Error("transformer infiller: windows of " + std::to_string(W) +
                  " frames, the network was built for " + std::to_string(net_.config().window));
    ValidMask both(static_cast<size_t>(W)), either(static_cast<size_t>(W));
    for (size_t t = 0; t < static_cast<size_t>(W); ++t) {
      both[t] = (w.valid[0][t] && w.valid[1][t]) ? 1 : 0;
      either[t] = (w.valid[0][t] || w.valid[1][t]) ? 1 : 0;
    }
    if (countValid(either) == 0) return w.features;  // nothing observed: keep the pre-fill
    const ValidMask& valid = countValid(both) > 0 ? both : either;
    const RowMatrixX<NetScalar> x = w.features.template cast<NetScalar>();
    InfillerWorkspace<NetScalar> ws(net_.config(), pool_ ? pool_->size() : 1);
    RowMatrixX<NetScalar> y;
    net_.forward(x, valid, y, ws, pool_);
    return y.template cast<Scalar>();
  }

 private:
  const InfillerNet<NetScalar>& net_;
  ThreadPool* pool_;
};

}  // namespace hawor
