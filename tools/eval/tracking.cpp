// SPDX-License-Identifier: LGPL-2.1-or-later
// Tracking figures of a video sequence, see tracking.hpp.
#include "tracking.hpp"

#include "metrics.hpp"

#include <algorithm>
#include <set>
#include <tuple>

namespace pickdetect::eval {

TrackingSummary score_tracking(const Dataset& dataset,
                               const std::map<size_t, std::vector<DetectedInstance>>& detected) {
  TrackingSummary t;
  using Id = std::optional<long long>;
  std::map<long long, Id> last_id;                        // True track -> id at last pairing.
  std::map<long long, std::set<long long>> ids_of;        // True track -> ids it was paired with.
  std::map<long long, long> required_frames;              // True track -> frames required.
  std::map<std::pair<long long, long long>, long> shared; // (true track, id) -> frames.
  std::map<long long, long> id_frames;                    // id -> frames it was seen in.
  const std::vector<DetectedInstance> none;
  for (size_t si = 0; si < dataset.scenes.size(); ++si) {
    const Scene& scene = dataset.scenes[si];
    auto it = detected.find(si);
    const std::vector<DetectedInstance>& dets = it == detected.end() ? none : it->second;
    std::set<long long> ids_here;
    for (const DetectedInstance& d : dets)
      if (d.track)
        ids_here.insert(*d.track);
    for (long long id : ids_here)
      id_frames[id]++;
    std::vector<bool> paired(scene.instances.size(), false);
    for (const ModelInfo& model : dataset.models) {
      const std::vector<Pairing> pairs = match_scene(scene, dets, model.name);
      for (size_t d = 0; d < dets.size(); ++d) {
        if (dets[d].model != model.name)
          continue;
        const int g = pairs[d].instance;
        if (g < 0) {
          t.fp++;
          t.detections++;
          continue;
        }
        const TrueInstance& truth = scene.instances[static_cast<size_t>(g)];
        if (truth.visible < kDontCareVisible)
          continue;
        t.detections++;
        paired[static_cast<size_t>(g)] = true;
        const long long object = truth.track.value_or(-1 - static_cast<long long>(si));
        const Id id = dets[d].track;
        auto last = last_id.find(object);
        if (last != last_id.end() && last->second != id)
          t.id_switches++;
        last_id[object] = id;
        if (id) {
          ids_of[object].insert(*id);
          shared[{object, *id}]++;
        }
      }
    }
    for (size_t g = 0; g < scene.instances.size(); ++g) {
      const TrueInstance& truth = scene.instances[g];
      if (truth.visible < kDontCareVisible)
        continue;
      t.required++;
      if (truth.track)
        required_frames[*truth.track]++;
      if (!paired[g])
        t.fn++;
    }
  }

  // IDTP: each true object with one id, one to one, by the most frames shared.
  std::vector<std::tuple<long, long long, long long>> order;
  for (const auto& [key, frames] : shared)
    order.emplace_back(-frames, key.first, key.second);
  std::sort(order.begin(), order.end());
  std::set<long long> objects_taken, ids_taken;
  for (const auto& [negative, object, id] : order) {
    if (objects_taken.count(object) || ids_taken.count(id))
      continue;
    objects_taken.insert(object);
    ids_taken.insert(id);
    t.idtp += -negative;
  }

  for (const auto& [object, frames] : required_frames) {
    if (frames < kTrackMinFrames)
      continue;
    t.objects_present++;
    t.objects_counted += objects_taken.count(object) ? 1 : 0;
    auto ids = ids_of.find(object);
    t.fragmented += ids != ids_of.end() && ids->second.size() > 1 ? 1 : 0;
  }
  for (const auto& [id, frames] : id_frames)
    t.ghosts += frames >= kTrackMinFrames && !ids_taken.count(id) ? 1 : 0;

  if (t.required > 0)
    t.mota = 1.0 - static_cast<double>(t.fn + t.fp + t.id_switches) / t.required;
  if (t.required + t.detections > 0)
    t.idf1 = 2.0 * t.idtp / static_cast<double>(t.required + t.detections);
  return t;
}

} // namespace pickdetect::eval
