#include "nn/safetensors.h"

#include <algorithm>
#include <bit>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <vector>

#include "graph/atomic_file.h"
#include "graph/error.h"

namespace weft::nn {

static_assert(std::endian::native == std::endian::little,
              "safetensors data is little-endian; weft reads it in place");

namespace {

using json = nlohmann::json;

// The reference implementation refuses headers above 100 MB; so do we, before allocating.
constexpr uint64_t kMaxHeaderBytes = 100u << 20;

const char* safetensors_dtype(DType d) {
  switch (d) {
    case DType::F32: return "F32";
    case DType::F64: return "F64";
    case DType::I64: return "I64";
  }
  return "?";
}

bool parse_dtype(const std::string& s, DType& out) {
  if (s == "F32") out = DType::F32;
  else if (s == "F64") out = DType::F64;
  else if (s == "I64") out = DType::I64;
  else return false;
  return true;
}

struct Entry {
  std::string name;
  DType dtype;
  Shape shape;
  uint64_t begin, end;
};

// Parses and checks one header entry; `data_bytes` is the size of the data section.
Entry parse_entry(const std::string& path, const std::string& name, const json& j,
                  uint64_t data_bytes) {
  auto bad = [&](const auto&... what) {
    fail("safetensors '", path, "': tensor '", name, "': ", what...);
  };
  if (!j.is_object()) bad("header entry is not a JSON object");
  Entry e;
  e.name = name;
  auto dt = j.find("dtype");
  if (dt == j.end() || !dt->is_string()) bad("missing string field 'dtype'");
  if (!parse_dtype(dt->get<std::string>(), e.dtype))
    bad("dtype '", dt->get<std::string>(), "' is not supported (expected F32, F64 or I64)");
  auto sh = j.find("shape");
  if (sh == j.end() || !sh->is_array()) bad("missing array field 'shape'");
  uint64_t numel = 1;
  for (const json& d : *sh) {
    if (!d.is_number_unsigned()) bad("shape ", sh->dump(), " holds a non-integer or negative size");
    const uint64_t n = d.get<uint64_t>();
    if (n > static_cast<uint64_t>(std::numeric_limits<int64_t>::max()) ||
        (n != 0 && numel > std::numeric_limits<uint64_t>::max() / 8 / n))
      bad("shape ", sh->dump(), " is too large");
    numel *= n;
    e.shape.push_back(static_cast<int64_t>(n));
  }
  auto off = j.find("data_offsets");
  if (off == j.end() || !off->is_array() || off->size() != 2 || !(*off)[0].is_number_unsigned() ||
      !(*off)[1].is_number_unsigned())
    bad("'data_offsets' must be two non-negative integers");
  e.begin = (*off)[0].get<uint64_t>();
  e.end = (*off)[1].get<uint64_t>();
  if (e.begin > e.end) bad("data_offsets [", e.begin, ", ", e.end, "] are reversed");
  if (e.end > data_bytes)
    bad("data_offsets [", e.begin, ", ", e.end, "] run past the data section (", data_bytes,
        " bytes; the file is truncated or corrupt)");
  const uint64_t expected = numel * dtype_size(e.dtype);
  if (e.end - e.begin != expected)
    bad("data_offsets [", e.begin, ", ", e.end, "] hold ", e.end - e.begin, " bytes but ",
        safetensors_dtype(e.dtype), " ", sh->dump(), " needs ", expected);
  return e;
}

}  // namespace

SafetensorsFile load_safetensors(const std::string& path) {
  std::error_code ec;
  const uint64_t file_bytes = std::filesystem::file_size(path, ec);
  if (ec) fail("safetensors '", path, "': cannot open: ", ec.message());
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("safetensors '", path, "': cannot open for reading");
  if (file_bytes < 8)
    fail("safetensors '", path, "': ", file_bytes,
         " bytes is too short for the 8-byte header length (truncated file?)");
  unsigned char len_bytes[8];
  in.read(reinterpret_cast<char*>(len_bytes), 8);
  uint64_t header_bytes = 0;
  for (int i = 7; i >= 0; --i) header_bytes = (header_bytes << 8) | len_bytes[i];
  if (header_bytes > kMaxHeaderBytes)
    fail("safetensors '", path, "': header length ", header_bytes,
         " is implausible (over 100 MB): not a safetensors file or corrupt");
  if (header_bytes > file_bytes - 8)
    fail("safetensors '", path, "': header length ", header_bytes, " exceeds the ",
         file_bytes - 8, " bytes after it (truncated file?)");
  std::string header(header_bytes, '\0');
  in.read(header.data(), static_cast<std::streamsize>(header_bytes));
  if (!in) fail("safetensors '", path, "': cannot read the header");
  const uint64_t data_bytes = file_bytes - 8 - header_bytes;

  json j = json::parse(header, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded())
    fail("safetensors '", path, "': the header is not valid JSON (corrupt file?)");
  if (!j.is_object()) fail("safetensors '", path, "': the header is not a JSON object");

  SafetensorsFile out;
  std::vector<Entry> entries;
  for (auto it = j.begin(); it != j.end(); ++it) {
    if (it.key() == "__metadata__") {
      if (!it->is_object())
        fail("safetensors '", path, "': '__metadata__' is not a JSON object");
      for (auto m = it->begin(); m != it->end(); ++m) {
        if (!m->is_string())
          fail("safetensors '", path, "': metadata '", m.key(), "' is not a string");
        out.metadata[m.key()] = m->get<std::string>();
      }
      continue;
    }
    entries.push_back(parse_entry(path, it.key(), *it, data_bytes));
  }

  // The tensors must tile the data section exactly: no overlap and no hole.
  std::vector<const Entry*> order;
  for (const Entry& e : entries) order.push_back(&e);
  std::sort(order.begin(), order.end(), [](const Entry* a, const Entry* b) {
    return a->begin != b->begin ? a->begin < b->begin : a->end < b->end;
  });
  uint64_t cursor = 0;
  for (const Entry* e : order) {
    if (e->begin < cursor)
      fail("safetensors '", path, "': tensor '", e->name, "' (bytes [", e->begin, ", ", e->end,
           "]) overlaps another tensor");
    if (e->begin > cursor)
      fail("safetensors '", path, "': bytes [", cursor, ", ", e->begin,
           ") of the data section belong to no tensor (before tensor '", e->name, "')");
    cursor = e->end;
  }
  if (cursor != data_bytes)
    fail("safetensors '", path, "': the data section has ", data_bytes,
         " bytes but its tensors cover ", cursor, " (trailing garbage or a corrupt header)");

  // Everything checked: read the data.
  for (const Entry* e : order) {
    Tensor t = Tensor::empty(e->shape, e->dtype);
    if (e->end > e->begin) {
      in.seekg(static_cast<std::streamoff>(8 + header_bytes + e->begin));
      in.read(static_cast<char*>(t.raw_data()), static_cast<std::streamsize>(e->end - e->begin));
      if (!in)
        fail("safetensors '", path, "': tensor '", e->name, "': cannot read its ",
             e->end - e->begin, " bytes");
    }
    out.tensors.emplace(e->name, std::move(t));
  }
  return out;
}

void save_safetensors(const std::string& path, const TensorMap& tensors,
                      const Metadata& metadata) {
  json header = json::object();
  uint64_t offset = 0;
  for (const auto& [name, t] : tensors) {
    if (name.empty() || name == "__metadata__")
      fail("safetensors '", path, "': invalid tensor name '", name, "'");
    if (!t.defined()) fail("safetensors '", path, "': tensor '", name, "' is undefined");
    json shape = json::array();
    for (int64_t d : t.shape()) shape.push_back(d);
    header[name] = {{"dtype", safetensors_dtype(t.dtype())},
                    {"shape", shape},
                    {"data_offsets", {offset, offset + t.nbytes()}}};
    offset += t.nbytes();
  }
  if (!metadata.empty()) header["__metadata__"] = metadata;
  std::string text = header.dump();
  text.append((8 - text.size() % 8) % 8, ' ');
  unsigned char len_bytes[8];
  for (int i = 0; i < 8; ++i) len_bytes[i] = static_cast<unsigned char>(text.size() >> (8 * i));

  write_file_atomically(path, [&](std::ostream& out) {
    out.write(reinterpret_cast<const char*>(len_bytes), 8);
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    for (const auto& [name, t] : tensors)
      out.write(static_cast<const char*>(t.raw_data()), static_cast<std::streamsize>(t.nbytes()));
  });
}

const Tensor& require_tensor(const SafetensorsFile& file, const std::string& path,
                             const std::string& name) {
  auto it = file.tensors.find(name);
  if (it == file.tensors.end())
    fail("safetensors '", path, "': missing tensor '", name, "'");
  return it->second;
}

}  // namespace weft::nn
