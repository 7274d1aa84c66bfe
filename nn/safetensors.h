#pragma once
// safetensors files (https://github.com/huggingface/safetensors): an 8-byte
// little-endian u64 header length N, N bytes of JSON header
//   {"name": {"dtype": "F32"|"F64"|"I64", "shape": [...], "data_offsets": [begin, end]},
//    "__metadata__": {"key": "value", ...}}
// then the raw little-endian tensor data; offsets count bytes from the start of the data
// section. weft reads and writes F32, F64 and I64 (the dtypes of weft tensors).
//
// Reading validates the whole file (header length, JSON, dtypes, shapes, offsets in
// range, neither overlapping nor leaving holes) before returning anything; every error
// names the file and, where one is at fault, the tensor. Writing is atomic: a temporary
// file in the same folder, fsync, rename over the target.
#include <map>
#include <string>

#include "graph/tensor.h"

namespace weft::nn {

using TensorMap = std::map<std::string, Tensor>;
using Metadata = std::map<std::string, std::string>;

struct SafetensorsFile {
  TensorMap tensors;  // each a fresh contiguous tensor owning its data
  Metadata metadata;  // "__metadata__", empty when absent
};

// Reads every tensor of `path`; throws weft::Error naming the file (and tensor) on any
// malformed, truncated or inconsistent content.
SafetensorsFile load_safetensors(const std::string& path);

// Writes `tensors` (names must be non-empty and not "__metadata__") and `metadata` to
// `path` atomically. The header is space-padded so the data section is 8-byte aligned.
void save_safetensors(const std::string& path, const TensorMap& tensors,
                      const Metadata& metadata = {});

// The tensor `name` of `file` (loaded from `path`), with an error naming both when absent.
const Tensor& require_tensor(const SafetensorsFile& file, const std::string& path,
                             const std::string& name);

}  // namespace weft::nn
