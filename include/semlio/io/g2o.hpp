#pragma once
/// \file
/// g2o pose-graph files: 3D `VERTEX_SE3:QUAT id x y z qx qy qz qw`,
/// `EDGE_SE3:QUAT i j x y z qx qy qz qw` + the 21 upper-triangle entries of
/// the 6x6 information (row-major, ordered [x y z qx qy qz]); 2D
/// `VERTEX_SE2 id x y theta`, `EDGE_SE2 i j dx dy dtheta` + 6 entries
/// (I11 I12 I13 I22 I23 I33); `FIX id`. Empty lines and `#` comments are
/// ignored; lines with other tags are skipped and counted. A file holds one
/// dimension only.
///
/// Information validation: every information matrix must be finite and
/// positive semi-definite (PSD). A bad one is repaired by projection to the
/// nearest PSD matrix in the Frobenius norm: non-finite entries are first set
/// to 0, the matrix is symmetrised, eigen-decomposed, and negative eigenvalues
/// are clamped to exactly 0 (no floor: an indefinite direction carries no
/// information afterwards; the solver reports a singular system if that
/// leaves a node unconstrained). Repairs are counted in
/// G2oGraph::repaired_information. With G2oReadConfig::strict the reader
/// instead throws FormatError naming path, line and the smallest eigenvalue
/// (or the non-finite entry). "Negative" means below -1e-12 * max|eigenvalue|.

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <charconv>
#include <cmath>
#include <cstddef>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/io/detail/text.hpp>
#include <semlio/graph/pose2.hpp>
#include <semlio/lie/se3.hpp>

namespace semlio::io {

/// Reader settings.
struct G2oReadConfig {
  bool strict = false;  ///< throw on a non-finite / non-PSD information instead of repairing it
};

/// A 3D vertex: g2o id and pose T_world_vertex.
struct G2oVertex3 {
  long id = 0;
  SE3d pose;
};
/// A 3D edge: measurement T_from^-1 T_to and 6x6 information ([x y z qx qy qz]).
struct G2oEdge3 {
  long from = 0;
  long to = 0;
  SE3d measured;
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Identity();
};
/// A 2D vertex: g2o id and pose.
struct G2oVertex2 {
  long id = 0;
  Pose2 pose;
};
/// A 2D edge: measurement and 3x3 information ([x y theta]).
struct G2oEdge2 {
  long from = 0;
  long to = 0;
  Pose2 measured;
  Eigen::Matrix3d information = Eigen::Matrix3d::Identity();
};

/// Contents of a g2o file (one of the 2D / 3D halves is empty).
struct G2oGraph {
  int dimension = 0;  ///< 2 or 3; 0 for a file without vertices and edges
  std::vector<G2oVertex3> vertices3;
  std::vector<G2oEdge3> edges3;
  std::vector<G2oVertex2> vertices2;
  std::vector<G2oEdge2> edges2;
  std::vector<long> fixed;               ///< ids from FIX lines
  std::size_t repaired_information = 0;  ///< information matrices projected to PSD
  std::size_t skipped_lines = 0;         ///< lines with tags other than the above
  long first_skipped_line = 0;           ///< line number of the first skipped line (0: none)
};

/// Result of a PSD check / repair.
struct PsdCheck {
  bool finite = true;           ///< all entries finite before the repair
  double min_eigenvalue = 0.0;  ///< smallest eigenvalue (after zeroing non-finite entries)
  bool repaired = false;        ///< the matrix was changed
};

/// Projects a symmetric matrix to the nearest PSD matrix in place (see the file comment).
template <int N>
PsdCheck project_to_psd(Eigen::Matrix<double, N, N>& M) {
  PsdCheck out;
  for (int r = 0; r < N; ++r) {
    for (int c = 0; c < N; ++c) {
      if (!std::isfinite(M(r, c))) {
        out.finite = false;
        M(r, c) = 0.0;
      }
    }
  }
  const Eigen::Matrix<double, N, N> S = 0.5 * (M + M.transpose());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> es(S);
  Eigen::Matrix<double, N, 1> lambda = es.eigenvalues();
  out.min_eigenvalue = lambda.minCoeff();
  const double tol = 1e-12 * std::max(lambda.cwiseAbs().maxCoeff(), 1e-300);
  const bool negative = out.min_eigenvalue < -tol;
  if (!out.finite || negative) {
    lambda = lambda.cwiseMax(0.0);
    const Eigen::Matrix<double, N, N> P = es.eigenvectors() * lambda.asDiagonal() * es.eigenvectors().transpose();
    M = 0.5 * (P + P.transpose());
    out.repaired = true;
  }
  return out;
}

namespace detail {

struct G2oLine {
  const std::string& path;
  long line;
  const std::vector<std::string_view>& tok;

  [[noreturn]] void fail(const std::string& what) const { throw FormatError(semlio::detail::where(path, line, what)); }

  void expect(std::size_t n) const {
    if (tok.size() != n) {
      fail(std::string(tok[0]) + ": expected " + std::to_string(n - 1) + " fields, got " +
           std::to_string(tok.size() - 1));
    }
  }
  [[nodiscard]] double number(std::size_t k) const {
    const std::string_view t = tok[k];
    double v = 0.0;
    const char* b = t.data();
    if (!t.empty() && t.front() == '+') ++b;
    const auto [ptr, ec] = std::from_chars(b, t.data() + t.size(), v);
    if (ec != std::errc() || ptr != t.data() + t.size())
      fail("field " + std::to_string(k) + ": not a number: '" + std::string(t) + "'");
    return v;
  }
  [[nodiscard]] long id(std::size_t k) const {
    const std::string_view t = tok[k];
    long v = 0;
    const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (ec != std::errc() || ptr != t.data() + t.size())
      fail("field " + std::to_string(k) + ": not an integer id: '" + std::string(t) + "'");
    return v;
  }
  [[nodiscard]] double finite(std::size_t k) const {
    const double v = number(k);
    if (!std::isfinite(v)) fail("field " + std::to_string(k) + ": non-finite value '" + std::string(tok[k]) + "'");
    return v;
  }
  [[nodiscard]] Eigen::Quaterniond quaternion(std::size_t k) const {
    const Eigen::Quaterniond q(finite(k + 3), finite(k), finite(k + 1), finite(k + 2));
    const double n = q.norm();
    if (!(std::abs(n - 1.0) < 1e-3))
      fail("quaternion norm " + std::to_string(n) + " is not 1 (fields " + std::to_string(k) + "-" +
           std::to_string(k + 3) + ")");
    return q.normalized();
  }
  template <int N>
  [[nodiscard]] Eigen::Matrix<double, N, N> information(std::size_t k, const G2oReadConfig& config,
                                                        std::size_t& repaired) const {
    Eigen::Matrix<double, N, N> M;
    for (int r = 0; r < N; ++r) {
      for (int c = r; c < N; ++c) {
        M(r, c) = number(k++);
        M(c, r) = M(r, c);
      }
    }
    Eigen::Matrix<double, N, N> copy = M;
    const PsdCheck check = project_to_psd<N>(copy);
    if (check.repaired) {
      if (config.strict) {
        if (!check.finite) fail("information matrix has a non-finite entry");
        std::ostringstream os;
        os.precision(6);
        os << "information matrix is not positive semi-definite: smallest eigenvalue " << check.min_eigenvalue;
        fail(os.str());
      }
      ++repaired;
      return copy;
    }
    return M;
  }
};

inline std::string format_double(double v) {
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, res.ptr);
}

}  // namespace detail

/// Parses g2o text already in memory (`path` names it in error messages).
/// Throws FormatError (path:line: wrong field count, non-number, non-unit
/// quaternion, mixed 2D/3D, duplicate vertex id, edge to an unknown vertex,
/// bad information in strict mode).
inline G2oGraph parse_g2o(std::string_view text, const std::string& path, const G2oReadConfig& config = {}) {
  G2oGraph g;
  std::unordered_map<long, long> first_line;     // vertex id -> line, for duplicates
  std::vector<std::pair<long, long>> edge_refs;  // (line, id) to check after reading
  auto set_dim = [&](int d, const detail::G2oLine& l) {
    if (g.dimension != 0 && g.dimension != d) l.fail("mixes 2D and 3D elements");
    g.dimension = d;
  };
  std::vector<std::string_view> tok;
  detail::for_each_line(text, [&](long number, std::string_view line) {
    detail::split_ws(line, tok);
    if (tok.empty() || tok[0].front() == '#') return;
    const detail::G2oLine l{path, number, tok};
    const std::string_view tag = tok[0];
    auto add_vertex = [&](long id) {
      const auto [it, inserted] = first_line.emplace(id, number);
      if (!inserted)
        l.fail("duplicate vertex id " + std::to_string(id) + " (first on line " + std::to_string(it->second) + ")");
    };
    if (tag == "VERTEX_SE3:QUAT") {
      l.expect(9);
      set_dim(3, l);
      G2oVertex3 v{.id = l.id(1),
                   .pose = SE3d(l.quaternion(5), Eigen::Vector3d(l.finite(2), l.finite(3), l.finite(4)))};
      add_vertex(v.id);
      g.vertices3.push_back(v);
    } else if (tag == "EDGE_SE3:QUAT") {
      l.expect(31);
      set_dim(3, l);
      G2oEdge3 e{.from = l.id(1),
                 .to = l.id(2),
                 .measured = SE3d(l.quaternion(6), Eigen::Vector3d(l.finite(3), l.finite(4), l.finite(5))),
                 .information = l.information<6>(10, config, g.repaired_information)};
      edge_refs.emplace_back(number, e.from);
      edge_refs.emplace_back(number, e.to);
      g.edges3.push_back(e);
    } else if (tag == "VERTEX_SE2") {
      l.expect(5);
      set_dim(2, l);
      G2oVertex2 v{.id = l.id(1), .pose = Pose2(l.finite(2), l.finite(3), l.finite(4))};
      add_vertex(v.id);
      g.vertices2.push_back(v);
    } else if (tag == "EDGE_SE2") {
      l.expect(12);
      set_dim(2, l);
      G2oEdge2 e{.from = l.id(1),
                 .to = l.id(2),
                 .measured = Pose2(l.finite(3), l.finite(4), l.finite(5)),
                 .information = l.information<3>(6, config, g.repaired_information)};
      edge_refs.emplace_back(number, e.from);
      edge_refs.emplace_back(number, e.to);
      g.edges2.push_back(e);
    } else if (tag == "FIX") {
      if (tok.size() < 2) l.fail("FIX: expected at least one vertex id");
      for (std::size_t k = 1; k < tok.size(); ++k) {
        g.fixed.push_back(l.id(k));
        edge_refs.emplace_back(number, g.fixed.back());
      }
    } else {
      if (g.skipped_lines == 0) g.first_skipped_line = number;
      ++g.skipped_lines;
    }
  });
  for (const auto& [ln, id] : edge_refs) {
    if (first_line.find(id) == first_line.end())
      throw FormatError(semlio::detail::where(path, ln, "unknown vertex id " + std::to_string(id)));
  }
  return g;
}

/// Reads a g2o file. Throws IoError (cannot open) or the FormatError of
/// parse_g2o.
inline G2oGraph read_g2o(const std::string& path, const G2oReadConfig& config = {}) {
  // Whole-file read: regular files only, bounded (a FIFO or device is an
  // IoError instead of a hang or an unbounded read).
  return parse_g2o(detail::read_file(path), path, config);
}

/// Writes a g2o graph to a stream (shortest round-trip decimal numbers).
inline void write_g2o(std::ostream& out, const G2oGraph& g) {
  const auto f = detail::format_double;
  auto info = [&](const auto& M) {
    for (int r = 0; r < M.rows(); ++r) {
      for (int c = r; c < M.cols(); ++c) out << ' ' << f(M(r, c));
    }
  };
  auto se3 = [&](const SE3d& T) {
    const Eigen::Quaterniond& q = T.so3().quaternion();
    const Eigen::Vector3d& t = T.translation();
    out << ' ' << f(t.x()) << ' ' << f(t.y()) << ' ' << f(t.z()) << ' ' << f(q.x()) << ' ' << f(q.y()) << ' '
        << f(q.z()) << ' ' << f(q.w());
  };
  auto se2 = [&](const Pose2& T) {
    out << ' ' << f(T.translation().x()) << ' ' << f(T.translation().y()) << ' ' << f(T.theta());
  };
  for (const G2oVertex3& v : g.vertices3) {
    out << "VERTEX_SE3:QUAT " << v.id;
    se3(v.pose);
    out << '\n';
  }
  for (const G2oVertex2& v : g.vertices2) {
    out << "VERTEX_SE2 " << v.id;
    se2(v.pose);
    out << '\n';
  }
  for (const long id : g.fixed) out << "FIX " << id << '\n';
  for (const G2oEdge3& e : g.edges3) {
    out << "EDGE_SE3:QUAT " << e.from << ' ' << e.to;
    se3(e.measured);
    info(e.information);
    out << '\n';
  }
  for (const G2oEdge2& e : g.edges2) {
    out << "EDGE_SE2 " << e.from << ' ' << e.to;
    se2(e.measured);
    info(e.information);
    out << '\n';
  }
}

/// Writes a g2o file (shortest round-trip decimal numbers). Throws IoError.
inline void write_g2o(const std::string& path, const G2oGraph& g) {
  std::ofstream out(path);
  if (!out) throw IoError(semlio::detail::where(path, 0, "cannot open g2o file for writing"));
  write_g2o(out, g);
  if (!out) throw IoError(semlio::detail::where(path, 0, "write failed"));
}

/// The text of a g2o graph (what write_g2o writes).
inline std::string format_g2o(const G2oGraph& g) {
  std::ostringstream out;
  write_g2o(out, g);
  return out.str();
}

}  // namespace semlio::io
