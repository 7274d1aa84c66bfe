#pragma once
// The detector's two loss terms (stages.detector.heatmaps and .mask in a training config;
// capture/training/training_config.h's loss_terms()), graphs of the engine's ops so that
// float32 training and the float64 gradient check run the same code.
#include "graph/tensor.h"

namespace weft::capture {

// L_hm: Σ_b,m w_bm Σ_cells (pred − target)² / Σ_b,m w_bm — the squared error of each
// keypoint's heatmap summed over its cells, weighted by the label's confidence (0 for an
// undetected keypoint), averaged over the weights. pred, target [B, 25, H, W]; w [B, 25].
// With no weight at all it is 0 (and has no gradient).
Tensor heatmap_loss(const Tensor& pred, const Tensor& target, const Tensor& weights);

// L_mask: the binary cross-entropy of the mask logits z against the mask y (0/1), mean
// over the cells: mean(softplus(z) − y·z), which is −[y log σ(z) + (1 − y) log(1 − σ(z))].
// logits, target [B, 1, h, h].
Tensor mask_loss(const Tensor& logits, const Tensor& target);

}  // namespace weft::capture
