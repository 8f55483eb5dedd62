// SPDX-License-Identifier: LGPL-2.1-or-later
// Voting: each match carries every principal point into the scene through the roto-translation
// (and scaling) given by its two keypoints.
#include <pickdetect/voting.hpp>

#include "guided_matching.hpp"
#include "median.hpp"
#include "model_scene.hpp"
#include "polygon.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <optional>

namespace pickdetect {

std::vector<Vote> cast_votes(const std::vector<Match>& matches,
                             const std::vector<cv::KeyPoint>& model_keypoints,
                             const std::vector<cv::KeyPoint>& scene_keypoints,
                             const std::vector<cv::Point2f>& principal_points, bool allow_scale) {
  std::vector<Vote> votes;
  votes.reserve(matches.size());
  for (const Match& m : matches) {
    const cv::KeyPoint& km = model_keypoints[m.model_point];
    const cv::KeyPoint& ks = scene_keypoints[m.scene_point];
    Vote v;
    // SIFT angles grow clockwise on screen (image y axis down), like our instance angles.
    double angle = std::fmod(static_cast<double>(ks.angle) - km.angle, 360.0);
    if (angle < 0.0)
      angle += 360.0;
    v.angle = static_cast<float>(angle);
    v.scale = allow_scale && km.size > 0.f ? ks.size / km.size : 1.f;
    const double rad = angle * CV_PI / 180.0;
    const double c = std::cos(rad) * v.scale, s = std::sin(rad) * v.scale;
    v.points.reserve(principal_points.size());
    for (const cv::Point2f& p : principal_points) {
      const double dx = p.x - km.pt.x, dy = p.y - km.pt.y;
      v.points.emplace_back(static_cast<float>(ks.pt.x + c * dx - s * dy),
                            static_cast<float>(ks.pt.y + s * dx + c * dy));
    }
    votes.push_back(std::move(v));
  }
  return votes;
}

namespace detail {
namespace {

/// The paper's step 3-5: per principal point, the mode of the cluster's votes; then the
/// similarity that best carries the model's principal points onto those modes.
bool pose_from_principal_points(const ModelScene& ms, const std::vector<int>& members,
                                bool allow_scale, Similarity& pose) {
  const size_t n_points = ms.model.principal_points.size();
  std::vector<cv::Point2f> modes(n_points);
  std::vector<cv::Point2f> estimates(members.size());
  for (size_t j = 0; j < n_points; ++j) {
    cv::Point2d sum(0, 0);
    for (size_t k = 0; k < members.size(); ++k) {
      estimates[k] = ms.votes[members[k]].points[j];
      sum += cv::Point2d(estimates[k].x, estimates[k].y);
    }
    const cv::Point2f mean(static_cast<float>(sum.x / members.size()),
                           static_cast<float>(sum.y / members.size()));
    modes[j] = mean_shift_mode(estimates, mean, ms.bandwidth);
  }
  if (n_points >= 2)
    return fit_similarity(ms.model.principal_points, modes, allow_scale, pose);
  // A single principal point fixes the position only: take the votes' median rotation/scale.
  std::vector<float> angles, scales;
  for (int i : members) {
    angles.push_back(ms.votes[i].angle);
    scales.push_back(ms.votes[i].scale);
  }
  pose.angle = detail::median(angles);
  pose.scale = detail::median(scales);
  const cv::Point2f at =
      Similarity{pose.angle, pose.scale, {0, 0}}.apply(ms.model.principal_points[0]);
  pose.translation = cv::Point2d(modes[0].x - at.x, modes[0].y - at.y);
  return true;
}

/// Votes of one instance agree on its rotation; those of a neighbour whose centre lies close
/// by mostly do not. Within a centre cluster, votes are grouped by rotation with a circular
/// mean shift of this bandwidth (degrees); each group is a hypothesis of its own.
constexpr double kRotationBandwidthDeg = 20.0;

/// A few matches can line up by chance within the inlier distance (a few pixels, see
/// refine.cpp); SIFT places true ones within about half a pixel. An instance resting on fewer
/// than kSparseInliers inliers must fit them with an RMS residual of at most kMaxSparseRmsPx:
/// on the development sets, true instances with 4-5 inliers measured 0.05-0.49 px, chance
/// alignments of 4 matches 1.6-4.8 px. (With more inliers the bound would not hold: a
/// similarity fitted on ten inliers spread over a tilted object leaves up to 2 px.)
constexpr size_t kSparseInliers = 6;
constexpr double kMaxSparseRmsPx = 1.25;
/// A face of a faint-print model found on fewer than kThinShortfall times min_matches inliers
/// also starts guided matching at its pose; the pose found stands beside it where it pairs at
/// least kThinGain times as many keypoints: as many again beside the bunch it was found on. (On
/// the real tote, poses that gained less were a logo's pose stretched over a box's narrow side.)
constexpr size_t kThinShortfall = 2;
constexpr size_t kThinGain = 2;
/// The automatic bandwidth is a share of the model picture's side: right for objects seen at
/// the picture's size. Seen smaller (the median of the votes' size ratios below
/// kNarrowerScale), neighbours' centres lie nearer in the frame than the bandwidth allows for,
/// and the votes of a box mostly under an identical one climb to the denser mode of the one on
/// top: the lower box made no hypothesis of its own (hard sets, docs/hard-sets.md). The votes
/// the instances found leave are then clustered a second time, at the bandwidth narrowed by
/// that scale (by no more than kLeastNarrowing). The first pass keeps the wide bandwidth: it
/// gathers the votes of a face foreshortened along one axis, which a narrow one splits.
constexpr double kNarrowerScale = 0.8;
constexpr double kLeastNarrowing = 0.25;

/// How many of the given matches fitted no other model about as well (see Ambiguity::Share).
int distinct_among(const ModelScene& ms, const std::vector<int>& idx) {
  return static_cast<int>(
      std::count_if(idx.begin(), idx.end(), [&](int i) { return !ms.matches[i].shared; }));
}

/// The pose a single match gives: its keypoints' rotation and size ratio, its model keypoint
/// carried onto its scene keypoint.
Similarity pose_of_match(const ModelScene& ms, int i) {
  const Match& m = ms.matches[i];
  Similarity pose{ms.votes[i].angle, ms.votes[i].scale, {0.0, 0.0}};
  const cv::Point2f at = pose.apply(ms.model_features.keypoints[m.model_point].pt);
  const cv::Point2f seen = ms.scene.keypoints[m.scene_point].pt;
  pose.translation = cv::Point2d(seen.x - at.x, seen.y - at.y);
  return pose;
}

/// The modes of a few scattered votes can put the pose some pixels off, beyond the inlier
/// distance, so that refining it finds no inliers (a small object voting with few matches).
/// Then the member whose own pose carries the most members within the inlier distance is
/// refined instead.
std::vector<int> refine_from_members(const ModelScene& ms, const std::vector<int>& members,
                                     bool allow_scale, const std::vector<char>& claimed,
                                     Similarity& pose) {
  int best = -1;
  size_t best_count = 1;
  for (int i : members) {
    if (claimed[i])
      continue;
    const Similarity candidate = pose_of_match(ms, i);
    const double tol = inlier_distance(ms, candidate.scale);
    size_t count = 0;
    for (int j : members) {
      const Match& m = ms.matches[j];
      const cv::Point2f d = candidate.apply(ms.model_features.keypoints[m.model_point].pt) -
                            ms.scene.keypoints[m.scene_point].pt;
      count += !claimed[j] && d.dot(d) <= tol * tol;
    }
    if (count > best_count) {
      best = i;
      best_count = count;
    }
  }
  if (best < 0)
    return {};
  pose = pose_of_match(ms, best);
  return refine_pose(ms, pose, allow_scale, claimed);
}

/// Claims the inliers of an instance, and with each the other matches of its scene feature
/// (the copies of a repeated part): one scene feature shows one object.
void claim(const ModelScene& ms, const std::vector<int>& in, std::vector<char>& claimed) {
  const int n = static_cast<int>(ms.matches.size());
  for (int i : in) {
    claimed[i] = 1;
    // Matches come ordered by scene feature: its other matches are the neighbours in the list.
    const int feature = ms.matches[i].scene_point;
    for (int j = i - 1; j >= 0 && ms.matches[j].scene_point == feature; --j)
      claimed[j] = 1;
    for (int j = i + 1; j < n && ms.matches[j].scene_point == feature; ++j)
      claimed[j] = 1;
  }
}

/// Splits a centre cluster's votes (indices into ms.votes) by their rotation, largest first.
std::vector<std::vector<int>> split_by_rotation(const ModelScene& ms,
                                                const std::vector<int>& members) {
  // Each vote's rotation as a unit vector: a vote lies within the bandwidth of an angle when
  // its dot product with that angle's unit vector is at least cos(bandwidth).
  const double window = std::cos(kRotationBandwidthDeg * CV_PI / 180.0);
  std::vector<cv::Point2d> unit(members.size());
  for (size_t k = 0; k < members.size(); ++k) {
    const double r = ms.votes[members[k]].angle * CV_PI / 180.0;
    unit[k] = cv::Point2d(std::cos(r), std::sin(r));
  }
  std::vector<double> modes;
  // Seeds: the first vote of each occupied bin of half a bandwidth (bin seeding, as for the
  // centres), at most 36 climbs however many votes the cluster has.
  constexpr int kBins = static_cast<int>(720.0 / kRotationBandwidthDeg) + 1;
  std::vector<char> seeded(kBins, 0);
  for (int seed : members) {
    const int bin = static_cast<int>(ms.votes[seed].angle / (kRotationBandwidthDeg / 2.0));
    if (bin < 0 || bin >= kBins || seeded[bin])
      continue;
    seeded[bin] = 1;
    double at = ms.votes[seed].angle;
    for (int it = 0; it < 50; ++it) {
      const double r = at * CV_PI / 180.0;
      const cv::Point2d dir(std::cos(r), std::sin(r));
      double sx = 0.0, sy = 0.0;
      int n = 0;
      for (const cv::Point2d& u : unit)
        if (u.dot(dir) >= window) {
          sx += u.x;
          sy += u.y;
          ++n;
        }
      if (n == 0)
        break;
      double next = std::atan2(sy, sx) * 180.0 / CV_PI;
      next = next < 0.0 ? next + 360.0 : next;
      const bool settled = angle_difference(next, at) < 0.01;
      at = next;
      if (settled)
        break;
    }
    const bool known = std::any_of(modes.begin(), modes.end(), [&](double m) {
      return angle_difference(m, at) < kRotationBandwidthDeg;
    });
    if (!known)
      modes.push_back(at);
  }
  std::vector<std::vector<int>> groups(modes.size());
  for (int i : members) {
    int best = -1;
    double best_d = kRotationBandwidthDeg;
    for (size_t m = 0; m < modes.size(); ++m) {
      const double d = angle_difference(ms.votes[i].angle, modes[m]);
      if (d <= best_d) {
        best = static_cast<int>(m);
        best_d = d;
      }
    }
    if (best >= 0)
      groups[best].push_back(i);
  }
  std::stable_sort(groups.begin(), groups.end(),
                   [](const auto& a, const auto& b) { return a.size() > b.size(); });
  return groups;
}

/// The hypotheses of centre clusters (indices into ms.votes), strongest first: the clusters,
/// or with refinement each one split by rotation.
std::vector<std::vector<int>> hypotheses_of(const ModelScene& ms, const Settings& s,
                                            std::vector<Cluster> clusters) {
  std::vector<std::vector<int>> out;
  for (Cluster& c : clusters) {
    if (!s.refine) {
      out.push_back(std::move(c.members));
      continue;
    }
    for (std::vector<int>& g : split_by_rotation(ms, c.members))
      out.push_back(std::move(g));
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const auto& a, const auto& b) { return a.size() > b.size(); });
  return out;
}

/// The second pass's bandwidth (see kNarrowerScale), or 0 when there is none: a bandwidth the
/// caller chose, the paper's plain voting (no instance claims its votes), or objects seen about
/// their picture's size or larger.
double narrowed_bandwidth(const ModelScene& ms, const Settings& s) {
  if (s.bandwidth > 0.0 || !s.refine || ms.votes.empty())
    return 0.0;
  std::vector<float> scales;
  scales.reserve(ms.votes.size());
  for (const Vote& v : ms.votes)
    scales.push_back(v.scale);
  const double scale = median(std::move(scales));
  if (!(scale < kNarrowerScale))
    return 0.0;
  return ms.bandwidth * std::max(scale, kLeastNarrowing);
}

} // namespace

std::vector<Instance> find_by_voting(const ModelScene& ms, const Settings& s) {
  // Hypotheses: the centre clusters (the paper); with refinement, each split by rotation.
  std::vector<std::vector<int>> hypotheses = hypotheses_of(ms, s, centre_clusters(ms));
  std::vector<Instance> found;
  std::vector<char> claimed(ms.matches.size(), 0);
  std::vector<const std::vector<int>*> weak;
  // A hypothesis becomes an instance, claiming its inliers, or is dropped (some kept as weak).
  auto consider = [&](const std::vector<int>& members, bool narrow) {
    if (narrow) {
      // A narrow cluster mostly claimed is a part of an instance found already; one of too
      // few votes is left too (the wide pass has offered guided matching its few-vote ones).
      const auto taken =
          std::count_if(members.begin(), members.end(), [&](int i) { return claimed[i] != 0; });
      if (static_cast<int>(members.size()) < s.min_matches ||
          2 * static_cast<size_t>(taken) > members.size())
        return;
    }
    if (static_cast<int>(members.size()) < s.min_matches) {
      if (members.size() >= kMinGuidedVotes)
        weak.push_back(&members);
      return;
    }
    Similarity pose;
    if (!pose_from_principal_points(ms, members, s.allow_scale, pose))
      return;
    Instance inst;
    inst.matches = static_cast<int>(members.size());
    inst.distinct_matches = inst.matches;
    place(inst, ms.model, pose);
    if (s.refine) {
      std::vector<int> in = refine_pose(ms, pose, s.allow_scale, claimed);
      if (static_cast<int>(in.size()) < s.min_matches)
        in = refine_from_members(ms, members, s.allow_scale, claimed, pose);
      cv::Matx33d h;
      const size_t fewest = static_cast<size_t>(std::max(1, s.min_matches));
      // Without allow_scale the objects keep the model's size: the pose stays rigid.
      if (in.size() < fewest) {
        // A face far off the picture plane: a similarity fits only a part of it, whatever it
        // is refitted on. Its hypothesis still stands if an affine map gathers its votes.
        if (!refine_foreshortened(ms, pose, s.allow_scale, members, claimed, in, h,
                                  std::max(fewest, kMinForeshortenedFewest))) {
          // Too few of its votes agree on one pose: for a model of faint print, a hypothesis of
          // two or three votes that one stray vote made look like more (below).
          if (members.size() >= kMinGuidedVotes)
            weak.push_back(&members);
          return;
        }
        place(inst, ms.model, h);
        // Votes left over from a face already found (its similarity took only a part of
        // them) are that face again, not another.
        if (std::any_of(found.begin(), found.end(), [&](const Instance& other) {
              return cv::pointPolygonTest(other.outline, inst.center, false) >= 0;
            }))
          return;
      } else if (refine_foreshortened(ms, pose, s.allow_scale, members, claimed, in, h,
                                      kMinForeshortenedMatches)) {
        place(inst, ms.model, h);
      } else if (s.allow_scale && refine_perspective(ms, pose, s.allow_scale, claimed, in, h)) {
        place(inst, ms.model, h);
      } else {
        refine_robustly(ms, in, s.allow_scale, pose);
        place(inst, ms.model, pose);
      }
      if (in.size() < kSparseInliers && inlier_rms(ms, in, inst.homography) > kMaxSparseRmsPx)
        return;
      claim(ms, in, claimed);
      inst.matches = static_cast<int>(in.size());
      inst.distinct_matches = distinct_among(ms, in);
      inst.support = scene_points(ms, in);
    } else {
      inst.support = scene_points(ms, members);
    }
    found.push_back(std::move(inst));
  };
  // Strongest first: a hypothesis claims its inliers before weaker ones may.
  for (const std::vector<int>& members : hypotheses)
    consider(members, false);
  // The votes the instances found leave, clustered again at a narrower bandwidth when the
  // objects are seen smaller than their picture (kNarrowerScale).
  const double narrow = narrowed_bandwidth(ms, s);
  std::vector<std::vector<int>> narrower;
  if (narrow > 0.0) {
    std::vector<int> left;
    std::vector<cv::Point2f> centres;
    for (size_t i = 0; i < ms.votes.size(); ++i)
      if (!claimed[i]) {
        left.push_back(static_cast<int>(i));
        centres.push_back(ms.votes[i].points[0]);
      }
    std::vector<Cluster> clusters = mean_shift_clusters(centres, narrow);
    for (Cluster& c : clusters)
      for (int& k : c.members)
        k = left[static_cast<size_t>(k)];
    narrower = hypotheses_of(ms, s, std::move(clusters));
    for (const std::vector<int>& members : narrower)
      consider(members, true);
  }
  if (!ms.model.faint_print() || (weak.empty() && found.empty()) || !s.refine || !s.allow_scale)
    return found;
  // A model of faint print (few keypoints, found at a lowered threshold: a white glossy carton)
  // leaves a face tilted far off the picture plane or under glare with two or three votes: most
  // of its matches fail the ratio test; a stray vote among them (a match elsewhere whose vote
  // for the centre lands near theirs) may make a hypothesis of min_matches votes that no pose
  // fits. Such hypotheses are completed by guided matching where the frame's keypoints bear
  // them out. Models of rich print keep the ratio test's word: in their clutter (the dev sets)
  // guided matching built ghosts of five to ten pairs. Its grids over every model and frame
  // keypoint are built on the first hypothesis that needs them: most frames have none.
  std::optional<GuidedMatcher> guided;
  auto matcher = [&]() -> const GuidedMatcher& {
    if (!guided)
      guided.emplace(ms);
    return *guided;
  };
  auto inside_found = [&](cv::Point2f p) {
    return std::any_of(found.begin(), found.end(), [&](const Instance& other) {
      return cv::pointPolygonTest(other.outline, p, false) >= 0;
    });
  };
  // An instance of guided matching: placed by its map, supported by its pairs.
  auto guided_instance = [&](const cv::Matx33d& h, std::vector<cv::Point2f> support) {
    Instance inst;
    place(inst, ms.model, h);
    inst.matches = static_cast<int>(support.size());
    inst.distinct_matches = inst.matches;
    inst.guided = true;
    inst.support = std::move(support);
    return inst;
  };
  auto complete = [&](const Similarity& pose) {
    if (inside_found(pose.apply(ms.model.principal_points[0])))
      return;
    cv::Matx33d h;
    std::vector<cv::Point2f> support;
    if (!matcher().complete(pose, h, support))
      return;
    Instance inst = guided_instance(h, std::move(support));
    if (!inside_found(inst.center))
      found.push_back(std::move(inst));
  };
  for (const std::vector<int>* members : weak) {
    Similarity pose;
    if (pose_from_principal_points(ms, *members, s.allow_scale, pose))
      complete(pose);
  }
  // Faces packed in a row beside one found: its neighbours' places, a face along each axis of
  // the picture, carried by its pose (a homography follows a foreshortened row).
  const cv::Rect2f side = bounds(ms.model.outline);
  const cv::Point2f c = ms.model.principal_points[0];
  // A found face's rotation and scale, its centre at `at`.
  auto pose_at = [&](const Instance& face, cv::Point2f at) {
    const Similarity turn{face.angle, face.scale, {}};
    const cv::Point2f to = at - turn.apply(c);
    return Similarity{face.angle, face.scale, cv::Point2d(to.x, to.y)};
  };
  const size_t first_found = found.size();
  for (size_t f = 0; f < first_found; ++f) {
    const cv::Matx33d h = found[f].homography;
    for (const cv::Point2f step : {cv::Point2f(side.width, 0.f), cv::Point2f(-side.width, 0.f),
                                   cv::Point2f(0.f, side.height), cv::Point2f(0.f, -side.height)}) {
      const cv::Vec3d q = h * cv::Vec3d(c.x + step.x, c.y + step.y, 1.0);
      if (!(q[2] > 0.0))
        continue;
      complete(pose_at(
          found[f], cv::Point2f(static_cast<float>(q[0] / q[2]), static_cast<float>(q[1] / q[2]))));
    }
  }
  // A face found on a few matches bunched in one part of it (the logo of a face tilted far
  // off the picture plane): its pose rests on that part alone, and the scene explanation may
  // find it too little spread. Guided matching from it pairs the rest of the face; where it
  // pairs as many again, its pose stands beside it as a guided instance (never pickable), which
  // the scene explanation weighs after every other: it takes the place only if the first fails.
  // A face guided matching completed has been paired over the whole of its outline already:
  // pairing it again from its own pose finds its own pairs (on beltA 3 of 370 such passes
  // paired twice as many, and the scene explanation kept none of those), at a third of a
  // millisecond each on the model's own thread.
  const size_t thin_below = kThinShortfall * static_cast<size_t>(std::max(1, s.min_matches));
  for (size_t f = 0; f < first_found; ++f) {
    const size_t matches = static_cast<size_t>(found[f].matches);
    if (matches >= thin_below || found[f].guided)
      continue;
    cv::Matx33d h;
    std::vector<cv::Point2f> support;
    if (matcher().complete(pose_at(found[f], found[f].points[0]), h, support, true) &&
        support.size() >= kThinGain * matches)
      found.push_back(guided_instance(h, std::move(support)));
  }
  return found;
}

} // namespace detail
} // namespace pickdetect
