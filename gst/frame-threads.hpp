// SPDX-License-Identifier: LGPL-2.1-or-later
// Frame threads of the pickdetect element (`threads` > 1): each input frame becomes a job on
// OrderedWorkers, frames go downstream in their order, serialized events wait for the frames
// before them, and the latency query counts the frames held back.
#pragma once

#include "frame.hpp"
#include "ordered-workers.hpp"

#include <gst/base/gstbasetransform.h>
#include <gst/gst.h>
#include <gst/video/video.h>

#include <functional>

namespace gstpickdetect {

/// The frames in the works of one element between start and stop. Streaming thread only.
class FrameThreads {
public:
  /// Takes the inputs of the next frame (under the element's lock); false, with an error
  /// posted, when the frame cannot be processed.
  using TakeInputs = std::function<bool(FrameInputs&)>;

  /// Tracks a frame detected on a frame thread and attaches its metas and messages, in frame
  /// order on the streaming thread (where the element's tracker lives).
  using AttachFrame = std::function<GstFlowReturn(GstBuffer* buffer, const FrameInputs& inputs,
                                                  const GstSegment& segment,
                                                  FrameDetection& found)>;
  /// Starts `threads` frame threads for `trans` (not owned: the element outlives them).
  FrameThreads(GstBaseTransform* trans, int threads, AttachFrame attach);

  /// GstBaseTransform::generate_output: the queued input frame goes to a frame thread, and the
  /// oldest frame comes out once done; waits only while every thread is busy. `parent` is the
  /// element's parent class (its prepare_output_buffer makes the input writable).
  GstFlowReturn generate_output(GstBaseTransformClass* parent, const TakeInputs& take_inputs,
                                GstBuffer** outbuf);

  /// Before a serialized event, so that events and frames keep their order, and at EOS: pushes
  /// every frame still in the works downstream, in order. A failed push is told at the next
  /// frame.
  void drain();

  /// FLUSH_STOP: drops every frame in the works (those not started are not detected).
  void flush();

private:
  GstFlowReturn push_all();

  GstBaseTransform* trans_;
  AttachFrame attach_;
  OrderedWorkers workers_;
  GstFlowReturn drain_ret_ = GST_FLOW_OK; ///< A failed push while draining.
};

/// Frame threads hold `threads` - 1 frames back: adds that much latency, at the frame rate of
/// `info`, to the answer of a latency query.
void add_frame_thread_latency(GstObject* element, GstQuery* query, int threads,
                              const GstVideoInfo& info);

} // namespace gstpickdetect
