#include "capture/io/camera.h"

#include <Eigen/LU>
#include <opencv2/core.hpp>
#include <opencv2/core/eigen.hpp>
#include <set>

#include "graph/atomic_file.h"
#include "files/text_reader.h"
#include "graph/error.h"

namespace weft::capture {

bool in_front(const Camera& camera, const Vertices& V) {
  for (int i = 0; i < V.rows(); ++i)
    if (camera.depth(V.row(i).transpose()) <= 1e-6) return false;
  return true;
}

Eigen::Vector2d Camera::project(const Eigen::Vector3d& X) const {
  const Eigen::Vector3d c = R * X + t;
  const double a = c.x() / c.z(), b = c.y() / c.z();
  const double r2 = a * a + b * b;
  const double k1 = dist(0), k2 = dist(1), p1 = dist(2), p2 = dist(3), k3 = dist(4);
  const double radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3));
  const double ad = a * radial + 2 * p1 * a * b + p2 * (r2 + 2 * a * a);
  const double bd = b * radial + p1 * (r2 + 2 * b * b) + 2 * p2 * a * b;
  return {K(0, 0) * ad + K(0, 1) * bd + K(0, 2), K(1, 1) * bd + K(1, 2)};
}

Points2 project_points(const Camera& camera, const Vertices& world) {
  Points2 out(world.rows(), 2);
  for (Eigen::Index i = 0; i < world.rows(); ++i) out.row(i) = camera.project(world.row(i).transpose()).transpose();
  return out;
}

void validate_camera(const Camera& c, const std::string& what) {
  if (!c.K.allFinite() || !(c.K(0, 0) > 0) || !(c.K(1, 1) > 0))
    fail(what, ": camera '", c.name, "' K must be finite with positive focal lengths");
  if (!c.dist.allFinite()) fail(what, ": camera '", c.name, "' has non-finite distortion");
  if (!c.R.allFinite() || (c.R.transpose() * c.R - Eigen::Matrix3d::Identity()).norm() > 1e-4 ||
      c.R.determinant() < 0)
    fail(what, ": camera '", c.name, "' R is not a rotation matrix");
  if (!c.t.allFinite()) fail(what, ": camera '", c.name, "' has a non-finite translation");
  if (c.width <= 0 || c.height <= 0)
    fail(what, ": camera '", c.name, "' image size ", c.width, "x", c.height, " must be positive");
}

// ---------------------------------------------------------------- FileStorage YAML

namespace {

cv::Mat read_matrix(const cv::FileNode& node, const std::string& where, const char* key, int rows,
                    std::initializer_list<int> cols) {
  const cv::FileNode n = node[key];
  if (n.empty()) fail(where, ": missing key '", key, "'");
  // The declared size is checked before OpenCV allocates it: a corrupt `rows: 400000000`
  // must be an error, not an attempt to allocate gigabytes.
  if (!n.isMap() || !n["rows"].isInt() || !n["cols"].isInt())
    fail(where, ": key '", key, "' is not an OpenCV matrix (!!opencv-matrix with rows, cols, dt, data)");
  const int declared_rows = static_cast<int>(n["rows"]), declared_cols = static_cast<int>(n["cols"]);
  if (declared_rows < 1 || declared_rows > 5 || declared_cols < 1 || declared_cols > 5)
    fail(where, ": key '", key, "' declares size ", declared_rows, "x", declared_cols, ", expected ",
         rows, "x", *cols.begin());
  cv::Mat m;
  try {
    n >> m;
  } catch (const cv::Exception& e) {
    fail(where, ": key '", key, "' is not an OpenCV matrix: ", e.what());
  }
  if (m.empty()) fail(where, ": key '", key, "' is not an OpenCV matrix (!!opencv-matrix)");
  bool ok = false;
  for (int c : cols) ok = ok || (m.rows == rows && m.cols == c) || (m.rows == c && m.cols == rows && rows == 1);
  if (!ok) fail(where, ": key '", key, "' has size ", m.rows, "x", m.cols, ", expected ", rows, "x", *cols.begin());
  m.convertTo(m, CV_64F);
  return m;
}

}  // namespace

std::vector<Camera> read_cameras_yaml(const std::string& path) {
  const std::string name = display_name(path);
  // FileStorage aborts on some malformed input only through exceptions; read the text
  // ourselves so a missing file gets our message.
  const std::string text = read_file_bytes(path);
  cv::FileStorage fs;
  try {
    fs.open(text, cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
  } catch (const cv::Exception& e) {
    fail(name, ": not a valid OpenCV FileStorage YAML file: ", e.err);
  } catch (const std::exception& e) {  // e.g. length_error from a corrupt string length
    fail(name, ": not a valid OpenCV FileStorage YAML file: ", e.what());
  }
  if (!fs.isOpened()) fail(name, ": not a valid OpenCV FileStorage YAML file");
  std::vector<Camera> cameras;
  try {
    const cv::FileNode list = fs["cameras"];
    if (list.empty() || !list.isSeq()) fail(name, ": expected a sequence 'cameras'");
    static const std::set<std::string> known{"name", "K", "dist", "R", "t", "image_width", "image_height"};
    int index = 0;
    for (auto it = list.begin(); it != list.end(); ++it, ++index) {
      const cv::FileNode node = *it;
      const std::string where = name + ": camera " + std::to_string(index);
      if (!node.isMap()) fail(where, ": expected a map with name, K, dist, R, t, image_width, image_height");
      for (const std::string& key : node.keys())
        if (!known.count(key)) fail(where, ": unknown key '", key, "'");
      Camera c;
      if (node["name"].empty() || !node["name"].isString()) fail(where, ": missing string key 'name'");
      c.name = static_cast<std::string>(node["name"]);
      const std::string at = where + " ('" + c.name + "')";
      cv::cv2eigen(read_matrix(node, at, "K", 3, {3}), c.K);
      const cv::Mat d = read_matrix(node, at, "dist", 1, {4, 5});
      for (int k = 0; k < static_cast<int>(d.total()); ++k) c.dist(k) = d.at<double>(k);
      cv::cv2eigen(read_matrix(node, at, "R", 3, {3}), c.R);
      const cv::Mat t = read_matrix(node, at, "t", 3, {1});
      for (int k = 0; k < 3; ++k) c.t(k) = t.at<double>(k);
      for (const char* key : {"image_width", "image_height"})
        if (node[key].empty() || !node[key].isInt()) fail(at, ": missing integer key '", key, "'");
      c.width = static_cast<int>(node["image_width"]);
      c.height = static_cast<int>(node["image_height"]);
      validate_camera(c, name);
      cameras.push_back(std::move(c));
    }
  } catch (const cv::Exception& e) {
    fail(name, ": malformed camera file: ", e.err);
  } catch (const weft::Error&) {
    throw;
  } catch (const std::exception& e) {
    fail(name, ": malformed camera file: ", e.what());
  }
  if (cameras.empty()) fail(name, ": 'cameras' is empty");
  return cameras;
}

void write_cameras_yaml(const std::string& path, const std::vector<Camera>& cameras) {
  for (const Camera& c : cameras) validate_camera(c, path);
  cv::FileStorage fs(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
  fs << "cameras" << "[";
  for (const Camera& c : cameras) {
    cv::Mat K, R, dist(1, 5, CV_64F), t(3, 1, CV_64F);
    cv::eigen2cv(c.K, K);
    cv::eigen2cv(c.R, R);
    for (int k = 0; k < 5; ++k) dist.at<double>(k) = c.dist(k);
    for (int k = 0; k < 3; ++k) t.at<double>(k) = c.t(k);
    fs << "{" << "name" << c.name << "image_width" << c.width << "image_height" << c.height << "K" << K
       << "dist" << dist << "R" << R << "t" << t << "}";
  }
  fs << "]";
  const std::string text = fs.releaseAndGetString();
  write_bytes_atomically(path, text.data(), text.size());
}

// ---------------------------------------------------------------- Skeletool .calibration

std::vector<Camera> read_skeletool_calibration(const std::string& path) {
  TextReader in(path);
  if (!in.next_nonempty_line()) in.fail_eof("'Skeletool Camera Calibration File V1.0'");
  if (in.line().find("Skeletool Camera Calibration") == std::string_view::npos)
    in.fail("expected 'Skeletool Camera Calibration File V1.0', found '", in.line(), "'");
  std::vector<Camera> cameras;
  Camera* cur = nullptr;
  std::set<std::string> seen;
  auto finish = [&]() {
    if (!cur) return;
    for (const char* key : {"size", "intrinsic", "extrinsic"})
      if (!seen.count(key)) in.fail("camera '", cur->name, "' has no '", key, "' line before this point");
    validate_camera(*cur, in.name());
  };
  while (in.next_nonempty_line()) {
    const auto& t = in.tokens();
    const std::string_view key = t[0];
    if (key == "name") {
      finish();
      in.expect_tokens(2, "name <camera name>");
      cameras.emplace_back();
      cur = &cameras.back();
      cur->name = t[1];
      seen.clear();
      continue;
    }
    if (!cur) in.fail("expected 'name <camera>' before '", key, "'");
    seen.insert(std::string(key));
    if (key == "sensor") {
      in.expect_tokens(3, "sensor <width mm> <height mm>");
      in.to_double(t[1], "sensor width");
      in.to_double(t[2], "sensor height");
    } else if (key == "size") {
      in.expect_tokens(3, "size <width px> <height px>");
      cur->width = static_cast<int>(in.to_int(t[1], "image width"));
      cur->height = static_cast<int>(in.to_int(t[2], "image height"));
    } else if (key == "animated") {
      in.expect_tokens(2, "animated 0");
      if (in.to_int(t[1], "animated flag") != 0) in.fail("animated cameras are not supported (expected 'animated 0')");
    } else if (key == "intrinsic" || key == "extrinsic") {
      in.expect_tokens(17, std::string(key) + " followed by 16 matrix entries");
      Eigen::Matrix4d M;
      for (int k = 0; k < 16; ++k) M(k / 4, k % 4) = in.to_double(t[k + 1], "matrix entry");
      if (key == "intrinsic") {
        cur->K = M.topLeftCorner<3, 3>();
      } else {
        cur->R = M.topLeftCorner<3, 3>();
        cur->t = M.block<3, 1>(0, 3);
      }
    } else if (key == "radial") {
      if (t.size() < 2 || t.size() > 4) in.fail("expected 'radial k1 [k2 [k3]]'");
      cur->dist.setZero();
      const int idx[3] = {0, 1, 4};
      for (size_t k = 1; k < t.size(); ++k) cur->dist(idx[k - 1]) = in.to_double(t[k], "radial coefficient");
    } else {
      in.fail("unknown calibration key '", key, "'");
    }
  }
  finish();
  if (cameras.empty()) in.fail("no cameras in calibration file");
  return cameras;
}

}  // namespace weft::capture
