#include "capture/detection/detection_losses.h"

#include "graph/error.h"
#include "ops/ops.h"

namespace weft::capture {

Tensor heatmap_loss(const Tensor& pred, const Tensor& target, const Tensor& weights) {
  WEFT_CHECK(pred.dim() == 4 && pred.shape() == target.shape() && weights.dim() == 2 &&
                 weights.size(0) == pred.size(0) && weights.size(1) == pred.size(1),
             "heatmap_loss: expected heatmaps [B, K, H, W] twice and weights [B, K], got ", shape_str(pred.shape()),
             ", ", shape_str(target.shape()), ", ", shape_str(weights.shape()));
  const Tensor diff = ops::sub(pred, target);
  const Tensor per_map = ops::sum(ops::mul(diff, diff), {2, 3});  // [B, K]
  const Tensor weighted = ops::sum(ops::mul(per_map, weights));
  double total = 0;
  const Tensor w = weights.to(DType::F64);
  for (int64_t i = 0; i < w.numel(); ++i) total += w.data<double>()[i];
  return ops::scale(weighted, total > 0 ? 1.0 / total : 0.0);
}

Tensor mask_loss(const Tensor& logits, const Tensor& target) {
  WEFT_CHECK(logits.dim() == 4 && logits.shape() == target.shape(),
             "mask_loss: expected logits and a target of one shape [B, 1, h, w], got ", shape_str(logits.shape()), " and ",
             shape_str(target.shape()));
  return ops::mean(ops::sub(ops::softplus(logits), ops::mul(target, logits)));
}

}  // namespace weft::capture
