// Peer comparison: semlio's pose-graph solver and Ceres on the same problem,
// in one run, so the time ratio comes from the same machine state.
//
//   bench_pgo_ceres [FILE.g2o ...]     (default: every graph in tests/data/posegraphs)
//
// Ceres solves exactly semlio's objective: residual U e with Omega = U^T U
// (U the UPPER Cholesky factor, so |U e|^2 = e^T Omega e; Ceres' own
// pose_graph_3d example whitens with the lower factor L and so minimises
// e^T L^T L e, a different objective), e the measurement-frame error
// [R_z^T(R_a^T(p_b - p_a) - p_z); 2 vec(q_z^-1 q_a^-1 q_b)] of
// semlio/graph/between_error.hpp, first vertex fixed (or the FIX vertices).
// Both report chi2 = sum e^T Omega e (Ceres: 2 * final cost), and Ceres'
// solution is re-evaluated with semlio's chi2 as a cross-check.
#include <ceres/ceres.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <chrono>
#include <ctime>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <unordered_map>
#include <vector>

#include <semlio/graph/pose_graph.hpp>
#include <semlio/io/g2o.hpp>
#include <semlio/io/g2o_graph.hpp>
#include <semlio_test/data.hpp>

namespace {

// Process CPU time [s]: on a shared machine wall time mostly measures the
// neighbours; both solvers are single-threaded here.
double cpu_s() { return static_cast<double>(std::clock()) / static_cast<double>(CLOCKS_PER_SEC); }

// U with U^T U = Omega: upper Cholesky, or the eigen square root when Omega is
// only semi-definite (a repaired matrix); both give |U e|^2 = e^T Omega e.
template <int N>
Eigen::Matrix<double, N, N> whitening(const Eigen::Matrix<double, N, N>& omega) {
  Eigen::LLT<Eigen::Matrix<double, N, N>> llt(omega);
  if (llt.info() == Eigen::Success) return llt.matrixU();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> es(omega);
  return es.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal() * es.eigenvectors().transpose();
}

struct Between3 {
  Eigen::Vector3d p_z;
  Eigen::Quaterniond q_z;
  Eigen::Matrix<double, 6, 6> U;

  template <typename T>
  bool operator()(const T* p_a_ptr, const T* q_a_ptr, const T* p_b_ptr, const T* q_b_ptr, T* residual_ptr) const {
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> p_a(p_a_ptr);
    const Eigen::Map<const Eigen::Quaternion<T>> q_a(q_a_ptr);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> p_b(p_b_ptr);
    const Eigen::Map<const Eigen::Quaternion<T>> q_b(q_b_ptr);
    const Eigen::Quaternion<T> q_a_inv = q_a.conjugate();
    const Eigen::Quaternion<T> q_z_inv = q_z.template cast<T>().conjugate();
    const Eigen::Matrix<T, 3, 1> p_ab = q_a_inv * (p_b - p_a);
    Eigen::Quaternion<T> q_e = q_z_inv * (q_a_inv * q_b);
    if (q_e.w() < T(0)) q_e.coeffs() = -q_e.coeffs();
    Eigen::Matrix<T, 6, 1> e;
    e.template head<3>() = q_z_inv * (p_ab - p_z.template cast<T>());
    e.template tail<3>() = T(2) * q_e.vec();
    Eigen::Map<Eigen::Matrix<T, 6, 1>> residual(residual_ptr);
    residual = U.template cast<T>() * e;
    return true;
  }
};

template <typename T>
T normalize_angle(const T& a) {
  const T two_pi(2.0 * std::numbers::pi);
  return a - two_pi * ceres::floor((a + T(std::numbers::pi)) / two_pi);
}

struct Between2 {
  Eigen::Vector2d p_z;
  double theta_z;
  Eigen::Matrix3d U;

  template <typename T>
  bool operator()(const T* a, const T* b, T* residual_ptr) const {
    using std::cos;
    using std::sin;
    const T ca = cos(a[2]);
    const T sa = sin(a[2]);
    const T dx = b[0] - a[0];
    const T dy = b[1] - a[1];
    const T tx = ca * dx + sa * dy - T(p_z.x());
    const T ty = -sa * dx + ca * dy - T(p_z.y());
    const T cz(std::cos(theta_z));
    const T sz(std::sin(theta_z));
    Eigen::Matrix<T, 3, 1> e;
    e << cz * tx + sz * ty, -sz * tx + cz * ty, normalize_angle(b[2] - a[2] - T(theta_z));
    Eigen::Map<Eigen::Matrix<T, 3, 1>> residual(residual_ptr);
    residual = U.template cast<T>() * e;
    return true;
  }
};

ceres::Solver::Options options() {
  ceres::Solver::Options o;
  o.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  o.max_num_iterations = 100;
  o.function_tolerance = 1e-12;
  o.gradient_tolerance = 1e-12;
  o.parameter_tolerance = 1e-12;
  o.num_threads = 1;
  return o;
}

struct Result {
  double chi2 = 0.0;
  double semlio_chi2_of_solution = 0.0;
  int iterations = 0;
  double seconds = 0.0;      // wall
  double cpu_seconds = 0.0;  // process CPU
};

Result ceres_3d(const semlio::io::G2oGraph& file) {
  std::vector<Eigen::Vector3d> p(file.vertices3.size());
  std::vector<Eigen::Quaterniond> q(file.vertices3.size());
  std::unordered_map<long, std::size_t> index;
  for (std::size_t k = 0; k < file.vertices3.size(); ++k) {
    p[k] = file.vertices3[k].pose.translation();
    q[k] = file.vertices3[k].pose.so3().quaternion();
    index[file.vertices3[k].id] = k;
  }
  ceres::Problem problem;
  for (const auto& e : file.edges3) {
    const std::size_t a = index.at(e.from);
    const std::size_t b = index.at(e.to);
    auto* cost = new ceres::AutoDiffCostFunction<Between3, 6, 3, 4, 3, 4>(
        new Between3{e.measured.translation(), e.measured.so3().quaternion(), whitening<6>(e.information)});
    problem.AddResidualBlock(cost, nullptr, p[a].data(), q[a].coeffs().data(), p[b].data(), q[b].coeffs().data());
  }
  for (std::size_t k = 0; k < q.size(); ++k) {
    if (problem.HasParameterBlock(q[k].coeffs().data()))
      problem.SetManifold(q[k].coeffs().data(), new ceres::EigenQuaternionManifold);
  }
  if (file.fixed.empty()) {
    problem.SetParameterBlockConstant(p[0].data());
    problem.SetParameterBlockConstant(q[0].coeffs().data());
  } else {
    for (const long id : file.fixed) {
      problem.SetParameterBlockConstant(p[index.at(id)].data());
      problem.SetParameterBlockConstant(q[index.at(id)].coeffs().data());
    }
  }
  ceres::Solver::Summary summary;
  const auto t0 = std::chrono::steady_clock::now();
  const double c0 = cpu_s();
  ceres::Solve(options(), &problem, &summary);
  Result r;
  r.cpu_seconds = cpu_s() - c0;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.chi2 = 2.0 * summary.final_cost;
  r.iterations = static_cast<int>(summary.iterations.size()) - 1;
  semlio::io::G2oGraph solved = file;
  for (std::size_t k = 0; k < p.size(); ++k) solved.vertices3[k].pose = semlio::SE3d(q[k], p[k]);
  r.semlio_chi2_of_solution = semlio::io::make_pose_graph3(solved).chi2();
  return r;
}

Result ceres_2d(const semlio::io::G2oGraph& file) {
  std::vector<Eigen::Vector3d> x(file.vertices2.size());
  std::unordered_map<long, std::size_t> index;
  for (std::size_t k = 0; k < file.vertices2.size(); ++k) {
    const auto& v = file.vertices2[k].pose;
    x[k] << v.translation(), v.theta();
    index[file.vertices2[k].id] = k;
  }
  ceres::Problem problem;
  for (const auto& e : file.edges2) {
    auto* cost = new ceres::AutoDiffCostFunction<Between2, 3, 3, 3>(
        new Between2{e.measured.translation(), e.measured.theta(), whitening<3>(e.information)});
    problem.AddResidualBlock(cost, nullptr, x[index.at(e.from)].data(), x[index.at(e.to)].data());
  }
  if (file.fixed.empty()) {
    problem.SetParameterBlockConstant(x[0].data());
  } else {
    for (const long id : file.fixed) problem.SetParameterBlockConstant(x[index.at(id)].data());
  }
  ceres::Solver::Summary summary;
  const auto t0 = std::chrono::steady_clock::now();
  const double c0 = cpu_s();
  ceres::Solve(options(), &problem, &summary);
  Result r;
  r.cpu_seconds = cpu_s() - c0;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.chi2 = 2.0 * summary.final_cost;
  r.iterations = static_cast<int>(summary.iterations.size()) - 1;
  semlio::io::G2oGraph solved = file;
  for (std::size_t k = 0; k < x.size(); ++k) solved.vertices2[k].pose = semlio::Pose2(x[k][0], x[k][1], x[k][2]);
  r.semlio_chi2_of_solution = semlio::io::make_pose_graph2(solved).chi2();
  return r;
}

template <typename Graph>
Result semlio_solve(Graph graph) {
  const auto t0 = std::chrono::steady_clock::now();
  const double c0 = cpu_s();
  const semlio::GraphSolveReport report = graph.optimize();
  Result r;
  r.cpu_seconds = cpu_s() - c0;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.chi2 = report.final_chi2;
  r.semlio_chi2_of_solution = graph.chi2();
  r.iterations = report.iterations;
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) files.emplace_back(argv[i]);
  if (files.empty()) {
    for (const char* name : {"tinyGrid3D", "smallGrid3D", "M3500", "parking-garage", "sphere2500"}) {
      files.push_back(semlio_test::data_path(std::string("posegraphs/") + name + ".g2o"));
    }
  }
  std::printf("%-22s %18s %18s %9s %9s %9s %9s %5s %5s %7s %9s\n", "graph", "semlio_chi2", "ceres_chi2", "semlio_s",
              "ceres_s", "s_cpu_s", "c_cpu_s", "it_s", "it_c", "ratio", "rel_diff");
  std::printf("(times: wall and process CPU seconds of the solve only; ratio = semlio CPU / Ceres CPU)\n");
  for (const std::string& path : files) {
    const semlio::io::G2oGraph file = semlio::io::read_g2o(path);
    const bool two_d = file.dimension == 2;
    const Result s =
        two_d ? semlio_solve(semlio::io::make_pose_graph2(file)) : semlio_solve(semlio::io::make_pose_graph3(file));
    const Result c = two_d ? ceres_2d(file) : ceres_3d(file);
    const std::string name = path.substr(path.find_last_of('/') + 1);
    std::printf("%-22s %18.10f %18.10f %9.4f %9.4f %9.4f %9.4f %5d %5d %7.3f %9.2e\n", name.c_str(), s.chi2, c.chi2,
                s.seconds, c.seconds, s.cpu_seconds, c.cpu_seconds, s.iterations, c.iterations,
                s.cpu_seconds / std::max(c.cpu_seconds, 1e-9), std::abs(s.chi2 - c.chi2) / c.chi2);
    std::printf("  (ceres solution re-evaluated by semlio: chi2 %.10f)\n", c.semlio_chi2_of_solution);
  }
  return 0;
}
