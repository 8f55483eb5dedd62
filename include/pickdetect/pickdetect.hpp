// SPDX-License-Identifier: LGPL-2.1-or-later
// The whole public API of the detection core: the detector, its settings and instances, models
// and model lists, features, calibration, errors. The stages of the method (matching.hpp,
// voting.hpp, meanshift.hpp, pose.hpp, ransac.hpp, occlusion.hpp) are internal: not installed,
// not exported.
#pragma once

#include <pickdetect/calibration.hpp>
#include <pickdetect/detector.hpp>
#include <pickdetect/error.hpp>
#include <pickdetect/export.hpp>
#include <pickdetect/feature_reuse.hpp>
#include <pickdetect/features.hpp>
#include <pickdetect/model.hpp>
#include <pickdetect/tracker.hpp>
