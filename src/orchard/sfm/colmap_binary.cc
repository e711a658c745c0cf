#include "orchard/sfm/colmap_binary.h"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"

namespace orchard {
namespace {

// COLMAP's camera model ids (src/base/camera_models.h).
const std::vector<std::string>& ModelNames() {
  static const std::vector<std::string> names = {
      "SIMPLE_PINHOLE", "PINHOLE", "SIMPLE_RADIAL", "RADIAL", "OPENCV", "OPENCV_FISHEYE",
      "FULL_OPENCV",    "FOV",     "SIMPLE_RADIAL_FISHEYE", "RADIAL_FISHEYE", "THIN_PRISM_FISHEYE"};
  return names;
}

class Reader {
 public:
  explicit Reader(const fs::path& path) : path_(path) {
    if (!fs::is_regular_file(path)) Fail("COLMAP binary model has no ", path.string());
    data_ = ReadTextFile(path);
  }
  template <typename T>
  T Get() {
    if (pos_ + sizeof(T) > data_.size()) Fail(path_.string(), ": truncated at byte ", pos_);
    T v;
    std::memcpy(&v, data_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  std::string GetString() {
    const size_t end = data_.find('\0', pos_);
    if (end == std::string::npos) Fail(path_.string(), ": truncated image name at byte ", pos_);
    std::string s = data_.substr(pos_, end - pos_);
    pos_ = end + 1;
    return s;
  }
  // Guards counts read from the file against absurd values (a corrupt file).
  std::uint64_t GetCount(size_t min_bytes_each) {
    const auto n = Get<std::uint64_t>();
    if (n > (data_.size() - pos_) / std::max<size_t>(1, min_bytes_each) + 1)
      Fail(path_.string(), ": count ", n, " at byte ", pos_ - 8, " exceeds the file");
    return n;
  }

 private:
  fs::path path_;
  std::string data_;
  size_t pos_ = 0;
};

class Writer {
 public:
  template <typename T>
  void Put(T v) {
    data_.append(reinterpret_cast<const char*>(&v), sizeof(T));
  }
  void PutString(const std::string& s) { data_.append(s).push_back('\0'); }
  const std::string& Data() const { return data_; }

 private:
  std::string data_;
};

}  // namespace

ColmapModel ReadColmapBinaryModel(const fs::path& dir) {
  if (!fs::is_directory(dir)) Fail("COLMAP model folder not found: ", dir.string());
  ColmapModel model;
  {
    Reader in(dir / "cameras.bin");
    for (std::uint64_t n = in.GetCount(24), i = 0; i < n; ++i) {
      ColmapCamera c;
      c.camera_id = static_cast<int>(in.Get<std::uint32_t>());
      const int model_id = in.Get<std::int32_t>();
      if (model_id < 0 || model_id >= static_cast<int>(ModelNames().size()))
        Fail((dir / "cameras.bin").string(), ": unknown camera model id ", model_id);
      c.model = ModelNames()[model_id];
      c.width = static_cast<int>(in.Get<std::uint64_t>());
      c.height = static_cast<int>(in.Get<std::uint64_t>());
      c.params.resize(ColmapCameraModelNumParams(c.model));
      for (double& p : c.params) p = in.Get<double>();
      model.cameras[c.camera_id] = c;
    }
  }
  {
    Reader in(dir / "images.bin");
    for (std::uint64_t n = in.GetCount(64), i = 0; i < n; ++i) {
      ColmapImage im;
      im.image_id = static_cast<int>(in.Get<std::uint32_t>());
      const double qw = in.Get<double>(), qx = in.Get<double>(), qy = in.Get<double>(), qz = in.Get<double>();
      im.qvec = Eigen::Quaterniond(qw, qx, qy, qz);
      for (int k = 0; k < 3; ++k) im.tvec[k] = in.Get<double>();
      im.camera_id = static_cast<int>(in.Get<std::uint32_t>());
      im.name = in.GetString();
      const std::uint64_t np = in.GetCount(24);
      im.points2D.resize(np);
      for (auto& p : im.points2D) {
        p.x = in.Get<double>();
        p.y = in.Get<double>();
        p.point3D_id = in.Get<std::int64_t>();  // COLMAP writes -1 (max uint64) for none
      }
      if (!model.cameras.count(im.camera_id))
        Fail((dir / "images.bin").string(), ": image ", im.image_id, " uses camera ", im.camera_id,
             ", which is not in cameras.bin");
      model.images[im.image_id] = std::move(im);
    }
  }
  {
    Reader in(dir / "points3D.bin");
    for (std::uint64_t n = in.GetCount(43), i = 0; i < n; ++i) {
      ColmapPoint3D p;
      p.point3D_id = static_cast<std::int64_t>(in.Get<std::uint64_t>());
      for (int k = 0; k < 3; ++k) p.xyz[k] = in.Get<double>();
      p.r = in.Get<std::uint8_t>(), p.g = in.Get<std::uint8_t>(), p.b = in.Get<std::uint8_t>();
      p.error = in.Get<double>();
      p.track.resize(in.GetCount(8));
      for (auto& t : p.track) {
        t.image_id = static_cast<int>(in.Get<std::uint32_t>());
        t.point2D_idx = static_cast<int>(in.Get<std::uint32_t>());
      }
      model.points3D[p.point3D_id] = std::move(p);
    }
  }
  return model;
}

void WriteColmapBinaryModel(const ColmapModel& model, const fs::path& dir) {
  fs::create_directories(dir);
  Writer cams;
  cams.Put<std::uint64_t>(model.cameras.size());
  for (const auto& [id, c] : model.cameras) {
    int model_id = -1;
    for (size_t k = 0; k < ModelNames().size(); ++k)
      if (ModelNames()[k] == c.model) model_id = static_cast<int>(k);
    if (model_id < 0) Fail("camera ", id, " has a model (", c.model, ") the binary format cannot store");
    cams.Put<std::uint32_t>(c.camera_id);
    cams.Put<std::int32_t>(model_id);
    cams.Put<std::uint64_t>(c.width);
    cams.Put<std::uint64_t>(c.height);
    for (double p : c.params) cams.Put<double>(p);
  }
  Writer ims;
  ims.Put<std::uint64_t>(model.images.size());
  for (const auto& [id, im] : model.images) {
    ims.Put<std::uint32_t>(im.image_id);
    for (double q : {im.qvec.w(), im.qvec.x(), im.qvec.y(), im.qvec.z()}) ims.Put<double>(q);
    for (int k = 0; k < 3; ++k) ims.Put<double>(im.tvec[k]);
    ims.Put<std::uint32_t>(im.camera_id);
    ims.PutString(im.name);
    ims.Put<std::uint64_t>(im.points2D.size());
    for (const auto& p : im.points2D) {
      ims.Put<double>(p.x);
      ims.Put<double>(p.y);
      ims.Put<std::int64_t>(p.point3D_id);
    }
  }
  Writer pts;
  pts.Put<std::uint64_t>(model.points3D.size());
  for (const auto& [id, p] : model.points3D) {
    pts.Put<std::uint64_t>(p.point3D_id);
    for (int k = 0; k < 3; ++k) pts.Put<double>(p.xyz[k]);
    pts.Put<std::uint8_t>(p.r), pts.Put<std::uint8_t>(p.g), pts.Put<std::uint8_t>(p.b);
    pts.Put<double>(p.error);
    pts.Put<std::uint64_t>(p.track.size());
    for (const auto& t : p.track) {
      pts.Put<std::uint32_t>(t.image_id);
      pts.Put<std::uint32_t>(t.point2D_idx);
    }
  }
  WriteTextFileAtomic(dir / "cameras.bin", cams.Data());
  WriteTextFileAtomic(dir / "images.bin", ims.Data());
  WriteTextFileAtomic(dir / "points3D.bin", pts.Data());
}

ColmapModel ReadColmapModel(const fs::path& dir) {
  if (fs::is_regular_file(dir / "cameras.txt")) return ReadColmapTextModel(dir);
  if (fs::is_regular_file(dir / "cameras.bin")) return ReadColmapBinaryModel(dir);
  if (!fs::is_directory(dir)) Fail("COLMAP model folder not found: ", dir.string());
  Fail("COLMAP model ", dir.string(), " has neither cameras.txt nor cameras.bin");
}

}  // namespace orchard
