#include "orchard/sfm/colmap_model.h"

#include <cerrno>
#include <cstdlib>
#include <sstream>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"

namespace orchard {
namespace {

// Splits a line on whitespace.
std::vector<std::string> Tokens(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> out;
  std::string token;
  while (in >> token) out.push_back(token);
  return out;
}

std::string Trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

// Where a parse error happened, for the message.
struct Where {
  const fs::path& path;
  int line;
};

double ParseDouble(const std::string& token, const Where& where, const char* what) {
  errno = 0;
  char* end = nullptr;
  const double value = std::strtod(token.c_str(), &end);
  if (token.empty() || end != token.c_str() + token.size() || errno == ERANGE) {
    Fail(where.path.string(), ":", where.line, ": ", what, " is not a number: '", token, "'");
  }
  return value;
}

std::int64_t ParseInt(const std::string& token, const Where& where, const char* what) {
  errno = 0;
  char* end = nullptr;
  const long long value = std::strtoll(token.c_str(), &end, 10);
  if (token.empty() || end != token.c_str() + token.size() || errno == ERANGE) {
    Fail(where.path.string(), ":", where.line, ": ", what, " is not an integer: '", token, "'");
  }
  return value;
}

std::vector<std::string> ReadLines(const fs::path& path) {
  std::istringstream in(ReadTextFile(path));
  std::vector<std::string> lines;
  std::string line;
  while (std::getline(in, line)) lines.push_back(line);
  return lines;
}

std::string FormatDouble(double v) {
  std::ostringstream out;
  out.precision(17);
  out << v;
  return out.str();
}

}  // namespace

const ColmapImage* ColmapModel::FindImage(const std::string& name) const {
  for (const auto& [id, image] : images) {
    if (image.name == name) return &image;
  }
  return nullptr;
}

int ColmapCameraModelNumParams(const std::string& model) {
  static const std::map<std::string, int> kNumParams = {
      {"SIMPLE_PINHOLE", 3}, {"PINHOLE", 4},         {"SIMPLE_RADIAL", 4},
      {"RADIAL", 5},         {"OPENCV", 8},          {"OPENCV_FISHEYE", 8},
      {"FULL_OPENCV", 12},   {"FOV", 5},             {"SIMPLE_RADIAL_FISHEYE", 4},
      {"RADIAL_FISHEYE", 5}, {"THIN_PRISM_FISHEYE", 12}};
  const auto it = kNumParams.find(model);
  if (it == kNumParams.end()) Fail("unknown COLMAP camera model '", model, "'");
  return it->second;
}

std::map<int, ColmapCamera> ReadColmapCamerasText(const fs::path& path) {
  std::map<int, ColmapCamera> cameras;
  const auto lines = ReadLines(path);
  for (size_t i = 0; i < lines.size(); ++i) {
    const std::string line = Trim(lines[i]);
    if (line.empty() || line[0] == '#') continue;
    const Where where{path, static_cast<int>(i + 1)};
    const auto tok = Tokens(line);
    if (tok.size() < 4) {
      Fail(path.string(), ":", where.line, ": expected CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]");
    }
    ColmapCamera camera;
    camera.camera_id = static_cast<int>(ParseInt(tok[0], where, "camera id"));
    camera.model = tok[1];
    int num_params = 0;
    try {
      num_params = ColmapCameraModelNumParams(camera.model);
    } catch (const Error& e) {
      Fail(path.string(), ":", where.line, ": ", e.what());
    }
    camera.width = static_cast<int>(ParseInt(tok[2], where, "width"));
    camera.height = static_cast<int>(ParseInt(tok[3], where, "height"));
    if (camera.width <= 0 || camera.height <= 0) {
      Fail(path.string(), ":", where.line, ": image size must be positive");
    }
    if (static_cast<int>(tok.size()) != 4 + num_params) {
      Fail(path.string(), ":", where.line, ": model ", camera.model, " needs ", num_params,
           " parameters, got ", tok.size() - 4);
    }
    for (int p = 0; p < num_params; ++p) camera.params.push_back(ParseDouble(tok[4 + p], where, "parameter"));
    if (!cameras.emplace(camera.camera_id, camera).second) {
      Fail(path.string(), ":", where.line, ": duplicate camera id ", camera.camera_id);
    }
  }
  return cameras;
}

std::map<int, ColmapImage> ReadColmapImagesText(const fs::path& path) {
  std::map<int, ColmapImage> images;
  const auto lines = ReadLines(path);
  for (size_t i = 0; i < lines.size(); ++i) {
    const std::string line = Trim(lines[i]);
    if (line.empty() || line[0] == '#') continue;
    const Where where{path, static_cast<int>(i + 1)};
    const auto tok = Tokens(line);
    if (tok.size() != 10) {
      Fail(path.string(), ":", where.line,
           ": expected IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME, got ", tok.size(), " fields");
    }
    ColmapImage image;
    image.image_id = static_cast<int>(ParseInt(tok[0], where, "image id"));
    const double qw = ParseDouble(tok[1], where, "qw"), qx = ParseDouble(tok[2], where, "qx"),
                 qy = ParseDouble(tok[3], where, "qy"), qz = ParseDouble(tok[4], where, "qz");
    image.qvec = Eigen::Quaterniond(qw, qx, qy, qz);
    if (!(image.qvec.norm() > 1e-9)) Fail(path.string(), ":", where.line, ": zero quaternion");
    for (int k = 0; k < 3; ++k) image.tvec[k] = ParseDouble(tok[5 + k], where, "translation");
    image.camera_id = static_cast<int>(ParseInt(tok[8], where, "camera id"));
    image.name = tok[9];
    // The next line (possibly empty) holds the 2D points: X Y POINT3D_ID triples.
    ++i;
    if (i < lines.size()) {
      const auto pts = Tokens(lines[i]);
      const Where pwhere{path, static_cast<int>(i + 1)};
      if (pts.size() % 3 != 0) {
        Fail(path.string(), ":", pwhere.line, ": 2D points line must hold X Y POINT3D_ID triples");
      }
      for (size_t k = 0; k < pts.size(); k += 3) {
        ColmapPoint2D p;
        p.x = ParseDouble(pts[k], pwhere, "point x");
        p.y = ParseDouble(pts[k + 1], pwhere, "point y");
        p.point3D_id = ParseInt(pts[k + 2], pwhere, "point3D id");
        image.points2D.push_back(p);
      }
    }
    if (!images.emplace(image.image_id, image).second) {
      Fail(path.string(), ":", where.line, ": duplicate image id ", image.image_id);
    }
  }
  return images;
}

std::map<std::int64_t, ColmapPoint3D> ReadColmapPoints3DText(const fs::path& path) {
  std::map<std::int64_t, ColmapPoint3D> points;
  const auto lines = ReadLines(path);
  for (size_t i = 0; i < lines.size(); ++i) {
    const std::string line = Trim(lines[i]);
    if (line.empty() || line[0] == '#') continue;
    const Where where{path, static_cast<int>(i + 1)};
    const auto tok = Tokens(line);
    if (tok.size() < 8 || (tok.size() - 8) % 2 != 0) {
      Fail(path.string(), ":", where.line,
           ": expected POINT3D_ID X Y Z R G B ERROR TRACK[] as (IMAGE_ID, POINT2D_IDX) pairs");
    }
    ColmapPoint3D point;
    point.point3D_id = ParseInt(tok[0], where, "point3D id");
    for (int k = 0; k < 3; ++k) point.xyz[k] = ParseDouble(tok[1 + k], where, "coordinate");
    point.r = static_cast<int>(ParseInt(tok[4], where, "red"));
    point.g = static_cast<int>(ParseInt(tok[5], where, "green"));
    point.b = static_cast<int>(ParseInt(tok[6], where, "blue"));
    point.error = ParseDouble(tok[7], where, "error");
    for (size_t k = 8; k < tok.size(); k += 2) {
      point.track.push_back({static_cast<int>(ParseInt(tok[k], where, "track image id")),
                             static_cast<int>(ParseInt(tok[k + 1], where, "track point index"))});
    }
    if (!points.emplace(point.point3D_id, point).second) {
      Fail(path.string(), ":", where.line, ": duplicate point3D id ", point.point3D_id);
    }
  }
  return points;
}

ColmapModel ReadColmapTextModel(const fs::path& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) Fail("COLMAP model folder not found: ", dir.string());
  for (const char* name : {"cameras.txt", "images.txt", "points3D.txt"}) {
    if (!fs::is_regular_file(dir / name, ec)) {
      Fail("COLMAP text model ", dir.string(), " has no ", name,
           " (binary models convert with `colmap model_converter --output_type TXT`)");
    }
  }
  ColmapModel model;
  model.cameras = ReadColmapCamerasText(dir / "cameras.txt");
  model.images = ReadColmapImagesText(dir / "images.txt");
  model.points3D = ReadColmapPoints3DText(dir / "points3D.txt");
  for (const auto& [id, image] : model.images) {
    if (!model.cameras.count(image.camera_id)) {
      Fail((dir / "images.txt").string(), ": image ", id, " uses camera ", image.camera_id,
           ", which is not in cameras.txt");
    }
  }
  return model;
}

std::string ColmapCamerasText(const std::map<int, ColmapCamera>& cameras) {
  std::ostringstream out;
  out << "# Camera list with one line of data per camera:\n"
      << "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
      << "# Number of cameras: " << cameras.size() << "\n";
  for (const auto& [id, camera] : cameras) {
    out << id << " " << camera.model << " " << camera.width << " " << camera.height;
    for (double p : camera.params) out << " " << FormatDouble(p);
    out << "\n";
  }
  return out.str();
}

std::string ColmapImagesText(const std::map<int, ColmapImage>& images) {
  size_t num_points = 0;
  for (const auto& [id, image] : images) num_points += image.points2D.size();
  std::ostringstream out;
  out << "# Image list with two lines of data per image:\n"
      << "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
      << "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
      << "# Number of images: " << images.size()
      << ", mean observations per image: "
      << (images.empty() ? 0.0 : static_cast<double>(num_points) / images.size()) << "\n";
  for (const auto& [id, image] : images) {
    const auto& q = image.qvec;
    out << id << " " << FormatDouble(q.w()) << " " << FormatDouble(q.x()) << " "
        << FormatDouble(q.y()) << " " << FormatDouble(q.z()) << " " << FormatDouble(image.tvec.x())
        << " " << FormatDouble(image.tvec.y()) << " " << FormatDouble(image.tvec.z()) << " "
        << image.camera_id << " " << image.name << "\n";
    for (size_t k = 0; k < image.points2D.size(); ++k) {
      const auto& p = image.points2D[k];
      out << (k ? " " : "") << FormatDouble(p.x) << " " << FormatDouble(p.y) << " " << p.point3D_id;
    }
    out << "\n";
  }
  return out.str();
}

std::string ColmapPoints3DText(const std::map<std::int64_t, ColmapPoint3D>& points3D) {
  std::ostringstream out;
  out << "# 3D point list with one line of data per point:\n"
      << "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
      << "# Number of points: " << points3D.size() << "\n";
  for (const auto& [id, p] : points3D) {
    out << id << " " << FormatDouble(p.xyz.x()) << " " << FormatDouble(p.xyz.y()) << " "
        << FormatDouble(p.xyz.z()) << " " << p.r << " " << p.g << " " << p.b << " "
        << FormatDouble(p.error);
    for (const auto& t : p.track) out << " " << t.image_id << " " << t.point2D_idx;
    out << "\n";
  }
  return out.str();
}

void WriteColmapTextModel(const ColmapModel& model, const fs::path& dir) {
  WriteTextFileAtomic(dir / "cameras.txt", ColmapCamerasText(model.cameras));
  WriteTextFileAtomic(dir / "images.txt", ColmapImagesText(model.images));
  WriteTextFileAtomic(dir / "points3D.txt", ColmapPoints3DText(model.points3D));
}

}  // namespace orchard
