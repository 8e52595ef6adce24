#pragma once
// A model card (YAML) -> semlio::OnnxModelCard (segment/onnx/onnx_segmenter.hpp),
// for --labels onnx --model CARD.yaml. Only `model` and `classes` are required;
// the defaults are RangeNet++'s KITTI card.
//
//   model: rangenet.onnx        # path of the ONNX file, relative to the card
//   image:
//     height_px: 64             # rows
//     width_px: 2048            # columns over 360 deg
//     fov_up_deg: 3.0           # elevation of the image's top edge [deg]
//     fov_down_deg: -25.0       # elevation of its bottom edge [deg]
//   channels:                   # the network's input order: range, x, y, z, intensity
//     - {name: range, mean: 12.12, std: 12.32}
//     - {name: x, mean: 10.88, std: 11.47}
//     - {name: y, mean: 0.23, std: 6.91}
//     - {name: z, mean: -1.04, std: 0.86}
//     - {name: intensity, mean: 0.21, std: 0.16}
//   classes: [unlabeled, car, bicycle, ...]   # output index -> learning class (name or id 0..19)
//   knn:                        # RangeNet++'s post-processing
//     enabled: true
//     search_px: 5              # window side (odd)
//     k: 5                      # neighbours that vote
//     sigma_px: 1.0             # Gaussian weighting of the window [pixels]
//     cutoff_m: 1.0             # farther in (weighted) range: no vote [m]
//
// Every problem (unknown key, bad value, missing key, an invalid result) is a
// semlio::ConfigError naming the file, the line and the key path.

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/segment/onnx/onnx_segmenter.hpp>
#include <semlio/segment/range_projection.hpp>

namespace semlio_examples {

namespace detail_model_card {

struct Reader {
  std::string path;

  [[nodiscard]] long line_of(const YAML::Node& n) const { return n.Mark().line >= 0 ? n.Mark().line + 1L : 0L; }

  [[noreturn]] void fail(const YAML::Node& n, const std::string& what) const {
    throw semlio::ConfigError(semlio::detail::where(path, line_of(n), what));
  }

  [[nodiscard]] static std::string shown(const YAML::Node& n) {
    return n.IsScalar() ? "'" + n.Scalar() + "'" : std::string("(not a scalar)");
  }

  [[nodiscard]] double number(const YAML::Node& n, const std::string& key) const {
    double v = 0.0;
    if (!n.IsScalar() || !YAML::convert<double>::decode(n, v) || !std::isfinite(v)) {
      fail(n, "'" + key + "' must be a finite number, got " + shown(n));
    }
    return v;
  }

  [[nodiscard]] int integer(const YAML::Node& n, const std::string& key) const {
    int v = 0;
    if (!n.IsScalar() || !YAML::convert<int>::decode(n, v)) fail(n, "'" + key + "' must be an integer, got " + shown(n));
    return v;
  }

  [[nodiscard]] bool boolean(const YAML::Node& n, const std::string& key) const {
    bool v = false;
    if (!n.IsScalar() || !YAML::convert<bool>::decode(n, v)) fail(n, "'" + key + "' must be true or false, got " + shown(n));
    return v;
  }

  [[nodiscard]] std::string text(const YAML::Node& n, const std::string& key) const {
    if (!n.IsScalar()) fail(n, "'" + key + "' must be a string, got " + shown(n));
    return n.Scalar();
  }

  // Calls f(key, value) for each entry of a map section; a non-scalar key is an error.
  template <typename F>
  void each(const YAML::Node& map, const std::string& section, F f) const {
    if (!map.IsMap()) fail(map, "'" + section + "' must be a map");
    for (const auto& kv : map) {
      if (!kv.first.IsScalar()) fail(kv.first, "a key in '" + section + "' is not a name");
      f(kv.first.Scalar(), kv.second, kv.first);
    }
  }

  [[noreturn]] void unknown(const YAML::Node& key_node, const std::string& key, const std::string& section,
                            const char* known) const {
    fail(key_node, "unknown key '" + (section.empty() ? key : section + "." + key) + "' (known: " + known + ")");
  }
};

inline semlio::Class class_named(const Reader& r, const YAML::Node& n, const std::string& key) {
  const std::string s = r.text(n, key);
  for (int id = 0; id < semlio::kNumClasses; ++id) {
    if (semlio::class_name(semlio::class_from_index(id)) == s) return semlio::class_from_index(id);
  }
  int id = -1;
  if (YAML::convert<int>::decode(n, id) && id >= 0 && id < semlio::kNumClasses) return semlio::class_from_index(id);
  r.fail(n, "'" + key + "' must be a learning class name (unlabeled, car, ..., traffic-sign) or id 0.." +
                std::to_string(semlio::kNumClasses - 1) + ", got '" + s + "'");
}

inline semlio::RangeChannel channel_named(const Reader& r, const YAML::Node& n, const std::string& key) {
  const std::string s = r.text(n, key);
  for (const semlio::RangeChannel c : {semlio::RangeChannel::kRange, semlio::RangeChannel::kX, semlio::RangeChannel::kY,
                                       semlio::RangeChannel::kZ, semlio::RangeChannel::kIntensity}) {
    if (semlio::range_channel_name(c) == s) return c;
  }
  r.fail(n, "'" + key + "' must be one of range, x, y, z, intensity, got '" + s + "'");
}

}  // namespace detail_model_card

/// Reads the model card `path`; the model path in it is taken relative to
/// the card's folder. Throws semlio::ConfigError (file, line, key) for any
/// problem, IoError when the card cannot be read. The model file itself is
/// opened by OnnxSegmenter.
inline semlio::OnnxModelCard load_model_card_yaml(const std::string& path) {
  namespace d = detail_model_card;
  const d::Reader r{path};
  YAML::Node root;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw semlio::IoError(path + ": model card not found");
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw semlio::IoError(path + ": cannot read the model card");
  } catch (const YAML::Exception& e) {
    throw semlio::ConfigError(semlio::detail::where(path, e.mark.line >= 0 ? e.mark.line + 1L : 0L,
                                                    "not valid YAML: " + e.msg));
  }
  if (!root.IsMap()) throw semlio::ConfigError(path + ": a model card must be a YAML map (model, image, channels, classes, knn)");
  semlio::OnnxModelCard card;
  bool have_model = false, have_classes = false;
  r.each(root, "", [&](const std::string& key, const YAML::Node& v, const YAML::Node& key_node) {
    if (key == "model") {
      const std::filesystem::path model(r.text(v, "model"));
      if (model.empty()) r.fail(v, "'model' is empty");
      card.model_path = (model.is_absolute() ? model : std::filesystem::path(path).parent_path() / model).string();
      have_model = true;
    } else if (key == "image") {
      semlio::RangeImageConfig& im = card.projection.image;
      r.each(v, "image", [&](const std::string& k, const YAML::Node& x, const YAML::Node& kn) {
        if (k == "height_px") {
          im.height_px = r.integer(x, "image.height_px");
        } else if (k == "width_px") {
          im.width_px = r.integer(x, "image.width_px");
        } else if (k == "fov_up_deg") {
          im.fov_up_rad = r.number(x, "image.fov_up_deg") * std::numbers::pi / 180.0;
        } else if (k == "fov_down_deg") {
          im.fov_down_rad = r.number(x, "image.fov_down_deg") * std::numbers::pi / 180.0;
        } else {
          r.unknown(kn, k, "image", "height_px, width_px, fov_up_deg, fov_down_deg");
        }
      });
    } else if (key == "channels") {
      if (!v.IsSequence() || v.size() == 0) r.fail(v, "'channels' must be a non-empty list of {name, mean, std}");
      card.projection.channels.clear();
      card.projection.channel_mean.clear();
      card.projection.channel_std.clear();
      for (std::size_t i = 0; i < v.size(); ++i) {
        const std::string at = "channels[" + std::to_string(i) + "]";
        bool name = false, mean = false, stddev = false;
        r.each(v[i], at, [&](const std::string& k, const YAML::Node& x, const YAML::Node& kn) {
          if (k == "name") {
            card.projection.channels.push_back(d::channel_named(r, x, at + ".name"));
            name = true;
          } else if (k == "mean") {
            card.projection.channel_mean.push_back(r.number(x, at + ".mean"));
            mean = true;
          } else if (k == "std") {
            const double s = r.number(x, at + ".std");
            if (!(s > 0.0)) r.fail(x, "'" + at + ".std' must be > 0, got " + d::Reader::shown(x));
            card.projection.channel_std.push_back(s);
            stddev = true;
          } else {
            r.unknown(kn, k, at, "name, mean, std");
          }
        });
        if (!(name && mean && stddev)) r.fail(v[i], "'" + at + "' needs name, mean and std");
      }
    } else if (key == "classes") {
      if (!v.IsSequence() || v.size() == 0) r.fail(v, "'classes' must be a non-empty list (output index -> class)");
      for (std::size_t i = 0; i < v.size(); ++i) {
        card.classes.push_back(d::class_named(r, v[i], "classes[" + std::to_string(i) + "]"));
      }
      have_classes = true;
    } else if (key == "knn") {
      semlio::RangeKnnConfig& k = card.projection.knn;
      r.each(v, "knn", [&](const std::string& kk, const YAML::Node& x, const YAML::Node& kn) {
        if (kk == "enabled") {
          k.enabled = r.boolean(x, "knn.enabled");
        } else if (kk == "search_px") {
          k.search_px = r.integer(x, "knn.search_px");
        } else if (kk == "k") {
          k.k = r.integer(x, "knn.k");
        } else if (kk == "sigma_px") {
          k.sigma_px = r.number(x, "knn.sigma_px");
        } else if (kk == "cutoff_m") {
          k.cutoff_m = r.number(x, "knn.cutoff_m");
        } else {
          r.unknown(kn, kk, "knn", "enabled, search_px, k, sigma_px, cutoff_m");
        }
      });
    } else {
      r.unknown(key_node, key, "", "model, image, channels, classes, knn");
    }
  });
  if (!have_model) throw semlio::ConfigError(path + ": the model card has no 'model' (path of the .onnx file)");
  if (!have_classes) throw semlio::ConfigError(path + ": the model card has no 'classes' (output index -> class)");
  try {
    semlio::RangeProjection::validate(card.projection);
  } catch (const semlio::ConfigError& e) {
    // The message names the field (image.*, channel*, knn.*): point at its section.
    const std::string what = e.what();
    const char* section = what.find(".image.") != std::string::npos ? "image"
                          : what.find(".knn.") != std::string::npos ? "knn"
                                                                   : "channels";
    const YAML::Node at = root[section];
    throw semlio::ConfigError(semlio::detail::where(path, at ? r.line_of(at) : 0L, "in '" + std::string(section) + "': " + what));
  }
  return card;
}

}  // namespace semlio_examples
