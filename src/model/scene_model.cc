#include "model/scene_model.h"

#include <chrono>

namespace hgrasp::model {

SceneModel ModelScene(const scan::RangeImage& range, const SceneModelConfig& config) {
  using Clock = std::chrono::steady_clock;
  const auto seconds_since = [](Clock::time_point t) {
    return std::chrono::duration<double>(Clock::now() - t).count();
  };
  SceneModel m;
  auto t = Clock::now();
  m.segments = segment::SegmentPlanes(range, config.segment);
  m.groups = segment::GroupObjects(m.segments, range, config.segment);
  m.segment_s = seconds_since(t);
  t = Clock::now();
  m.boxes = FitBoxes(m.segments, m.groups, range, &m.unfitted, config.box_fit);
  m.table_rgb = TableColour(m.segments, m.groups.floor_or_wall, range);
  for (const BoxModel& box : m.boxes) {
    m.textures.push_back(MakeFaceTextures(box, m.segments, range, config.texture_size));
    m.colours.push_back(BoxColour(m.segments, box.regions, range, m.table_rgb));
  }
  m.model_s = seconds_since(t);
  return m;
}

}  // namespace hgrasp::model
