#include "tools/mrpt/nav_ekf.hpp"

#include <mrpt/bayes/CKalmanFilterCapable.h>

#include <cmath>

#include "framework/units.hpp"

namespace driftlab::mrpt_bridge {

double wrap_angle(double rad) {
  constexpr double two_pi = 2.0 * kPi;
  double r = std::remainder(rad, two_pi);  // [-pi, pi]
  if (r <= -kPi) r += two_pi;
  return r;
}

namespace {
constexpr std::size_t kVeh = 4, kObs = 2, kFeat = 0, kAct = 3;
using Base = mrpt::bayes::CKalmanFilterCapable<kVeh, kObs, kFeat, kAct, double>;
}  // namespace

class NavEkf::Impl : public Base {
 public:
  Impl(const NavNoise& noise, const NavState& initial) : noise_(noise) {
    KF_options.method = mrpt::bayes::kfEKFNaive;  // kfIKF throws in MRPT 2.5.8
    KF_options.use_analytic_transition_jacobian = true;
    KF_options.use_analytic_observation_jacobian = true;
    setMinLoggingLevel(mrpt::system::LVL_ERROR);  // library code never prints
    getProfiler().enable(false);                  // (the profiler dumps its table on destruction)
    m_xkk.resize(kVeh);
    m_xkk[0] = initial.x_m;
    m_xkk[1] = initial.y_m;
    m_xkk[2] = wrap_angle(initial.heading_rad);
    m_xkk[3] = initial.bias_rad_s;
    m_pkk.setSize(kVeh, kVeh);
    for (std::size_t i = 0; i < kVeh; ++i)
      for (std::size_t j = 0; j < kVeh; ++j) m_pkk(i, j) = initial.covariance(i, j);
  }

  void step(double dt, double rate, double speed, std::optional<Eigen::Vector2d> fix) {
    dt_ = dt;
    rate_ = rate;
    speed_ = speed;
    fix_ = fix;
    runOneKalmanIteration();
  }

  NavState state() const {
    NavState s;
    s.x_m = m_xkk[0];
    s.y_m = m_xkk[1];
    s.heading_rad = m_xkk[2];
    s.bias_rad_s = m_xkk[3];
    for (std::size_t i = 0; i < kVeh; ++i)
      for (std::size_t j = 0; j < kVeh; ++j) s.covariance(i, j) = m_pkk(i, j);
    return s;
  }

 protected:
  void OnGetAction(KFArray_ACT& u) const override {
    u[0] = rate_;
    u[1] = speed_;
    u[2] = dt_;
  }

  void OnTransitionModel(const KFArray_ACT& u, KFArray_VEH& x, bool& skip) const override {
    skip = false;
    const double dt = u[2], v = u[1];
    const double dpsi = (u[0] - x[3]) * dt;
    const double mid = x[2] + 0.5 * dpsi;
    x[0] += v * dt * std::cos(mid);
    x[1] += v * dt * std::sin(mid);
    x[2] = wrap_angle(x[2] + dpsi);
  }

  void OnTransitionJacobian(KFMatrix_VxV& F) const override {
    const double dt = dt_, v = speed_;
    const double mid = m_xkk[2] + 0.5 * (rate_ - m_xkk[3]) * dt;
    const double c = std::cos(mid), s = std::sin(mid);
    F.setIdentity();
    F(0, 2) = -v * dt * s;
    F(0, 3) = v * dt * s * 0.5 * dt;
    F(1, 2) = v * dt * c;
    F(1, 3) = -v * dt * c * 0.5 * dt;
    F(2, 3) = -dt;
  }

  void OnTransitionNoise(KFMatrix_VxV& Q) const override {
    const double dt = dt_;
    const double mid = m_xkk[2];
    const double c = std::cos(mid), s = std::sin(mid);
    const double q_dist = std::pow(noise_.speed_sigma_mps * dt, 2);
    const double b = noise_.bias_instability_rad_s;
    const double q_bias = (std::pow(noise_.rate_random_walk_rad_s_sqrt_s, 2) +
                           (noise_.bias_correlation_time_s > 0 ? 2.0 * b * b / noise_.bias_correlation_time_s : 0.0)) *
                          dt;
    Q.setZero();
    Q(0, 0) = q_dist * c * c;
    Q(0, 1) = Q(1, 0) = q_dist * c * s;
    Q(1, 1) = q_dist * s * s;
    Q(2, 2) = std::pow(noise_.arw_rad_sqrt_s, 2) * dt;
    Q(3, 3) = q_bias;
  }

  void OnGetObservationNoise(KFMatrix_OxO& R) const override {
    const double r = noise_.fix_sigma_m * noise_.fix_sigma_m;
    R.setZero();
    R(0, 0) = r;
    R(1, 1) = r;
  }

  void OnGetObservationsAndDataAssociation(vector_KFArray_OBS& z, std::vector<int>& association,
                                           const vector_KFArray_OBS&, const KFMatrix&, const std::vector<size_t>&,
                                           const KFMatrix_OxO&) override {
    z.clear();
    association.clear();  // no map: an empty association is allowed with feature size 0
    if (!fix_) return;
    KFArray_OBS obs;
    obs[0] = (*fix_)[0];
    obs[1] = (*fix_)[1];
    z.push_back(obs);
  }

  // Without a map MRPT asks for predictions of zero landmarks but uses one: always return one.
  void OnObservationModel(const std::vector<size_t>&, vector_KFArray_OBS& predictions) const override {
    predictions.resize(1);
    predictions[0][0] = m_xkk[0];
    predictions[0][1] = m_xkk[1];
  }

  void OnObservationJacobians(size_t, KFMatrix_OxV& Hx, KFMatrix_OxF&) const override {
    Hx.setZero();
    Hx(0, 0) = 1.0;
    Hx(1, 1) = 1.0;
  }

  void OnNormalizeStateVector() override { m_xkk[2] = wrap_angle(m_xkk[2]); }

 private:
  NavNoise noise_;
  double dt_ = 0.0, rate_ = 0.0, speed_ = 0.0;
  std::optional<Eigen::Vector2d> fix_;
};

NavEkf::NavEkf(const NavNoise& noise, const NavState& initial) : impl_(std::make_unique<Impl>(noise, initial)) {}
NavEkf::~NavEkf() = default;

void NavEkf::step(double dt_s, double rate_rad_s, double speed_mps, std::optional<Eigen::Vector2d> fix_m) {
  impl_->step(dt_s, rate_rad_s, speed_mps, fix_m);
}

NavState NavEkf::state() const { return impl_->state(); }

}  // namespace driftlab::mrpt_bridge
