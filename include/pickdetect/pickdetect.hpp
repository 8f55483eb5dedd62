// SPDX-License-Identifier: LGPL-2.1-or-later
// The whole public API of the detection core.
#pragma once

#include <pickdetect/calibration.hpp>
#include <pickdetect/detector.hpp>
#include <pickdetect/error.hpp>
#include <pickdetect/features.hpp>
#include <pickdetect/matching.hpp>
#include <pickdetect/meanshift.hpp>
#include <pickdetect/model.hpp>
#include <pickdetect/occlusion.hpp>
#include <pickdetect/pose.hpp>
#include <pickdetect/ransac.hpp>
#include <pickdetect/tracker.hpp>
#include <pickdetect/voting.hpp>
