#include "plugins/builtins.hpp"

#include "framework/registry.hpp"

namespace driftlab {

void register_ga_plugins(Registry&);
void register_rbf_plugins(Registry&);
void register_sample_entropy_plugins(Registry&);
void register_kalman_plugins(Registry&);
void register_emd_plugins(Registry&);
void register_effect_plugins(Registry&);
void register_vmd_plugins(Registry&);
void register_polynomial_plugins(Registry&);
void register_wavelet_plugins(Registry&);
void register_tfpf_plugins(Registry&);
void register_pagmo_plugins(Registry&);
void register_elm_plugins(Registry&);
void register_svr_plugins(Registry&);
void register_rate_of_change_plugins(Registry&);

void register_builtin_plugins(Registry& registry) {
  register_ga_plugins(registry);
  register_rbf_plugins(registry);
  register_sample_entropy_plugins(registry);
  register_kalman_plugins(registry);
  register_emd_plugins(registry);
  register_effect_plugins(registry);
  register_vmd_plugins(registry);
  register_polynomial_plugins(registry);
  register_wavelet_plugins(registry);
  register_tfpf_plugins(registry);
  register_pagmo_plugins(registry);
  register_elm_plugins(registry);
  register_svr_plugins(registry);
  register_rate_of_change_plugins(registry);
}

}  // namespace driftlab
