#pragma once
/// @file algid.hpp
/// Umbrella header: every public algid header, nothing else.

#include "algid/algebraic_system.hpp"
#include "algid/algebraic_windows.hpp"
#include "algid/chain_config.hpp"
#include "algid/chain_estimator.hpp"
#include "algid/change_detector.hpp"
#include "algid/continuous_error.hpp"
#include "algid/continuous_estimator.hpp"
#include "algid/cramer.hpp"
#include "algid/histories.hpp"
#include "algid/input_screen.hpp"
#include "algid/integrator_chain.hpp"
#include "algid/joint_sum.hpp"
#include "algid/quadrature.hpp"
#include "algid/ratio_estimator.hpp"
#include "algid/robust_tracks.hpp"
#include "algid/types.hpp"
#include "algid/weak_form.hpp"
#include "algid/weak_form_source.hpp"
