// SPDX-License-Identifier: LGPL-2.1-or-later
#include "frame-threads.hpp"

#include <memory>
#include <utility>

GST_DEBUG_CATEGORY_EXTERN(gst_pick_detect_debug);
#define GST_CAT_DEFAULT gst_pick_detect_debug

namespace gstpickdetect {
namespace {

/// One frame on a frame thread. Owns its buffer until it is handed downstream.
class FrameJob final : public OrderedWorkers::Job {
public:
  FrameJob(GstElement* element, const FrameThreads::AttachFrame& attach, GstBuffer* buffer,
           FrameInputs inputs, const GstSegment& segment)
      : element_(element), attach_(attach), buffer_(buffer), in_(std::move(inputs)),
        segment_(segment) {}
  ~FrameJob() override {
    if (buffer_)
      gst_buffer_unref(buffer_);
  }
  FrameJob(const FrameJob&) = delete;
  FrameJob& operator=(const FrameJob&) = delete;

  void run() override {
    ret_ = detect_frame(element_, buffer_, *in_.format, in_.config, *in_.detector, found_);
  }

  /// Tracks the frame and attaches its metas and messages (in frame order, on the streaming
  /// thread), and hands over the buffer (null when the frame failed).
  GstBuffer* finish(GstFlowReturn& ret) {
    if (ret_ == GST_FLOW_OK)
      ret_ = attach_(buffer_, in_, segment_, found_);
    ret = ret_;
    GstBuffer* out = ret_ == GST_FLOW_OK ? buffer_ : nullptr;
    if (out)
      buffer_ = nullptr;
    return out;
  }

private:
  GstElement* element_;                   ///< Not owned: the element outlives its workers.
  const FrameThreads::AttachFrame& attach_; ///< The FrameThreads' own, which outlive their jobs.
  GstBuffer* buffer_;
  FrameInputs in_;
  GstSegment segment_;
  FrameDetection found_;
  GstFlowReturn ret_ = GST_FLOW_OK;
};

} // namespace

FrameThreads::FrameThreads(GstBaseTransform* trans, int threads, AttachFrame attach)
    : trans_(trans), attach_(std::move(attach)), workers_(threads) {}

GstFlowReturn FrameThreads::push_all() {
  GstFlowReturn result = GST_FLOW_OK;
  while (std::unique_ptr<OrderedWorkers::Job> job = workers_.take_oldest(true)) {
    GstFlowReturn ret = GST_FLOW_OK;
    GstBuffer* out = static_cast<FrameJob*>(job.get())->finish(ret);
    if (out && result == GST_FLOW_OK)
      ret = gst_pad_push(GST_BASE_TRANSFORM_SRC_PAD(trans_), out);
    else if (out)
      gst_buffer_unref(out);
    if (result == GST_FLOW_OK)
      result = ret;
  }
  return result;
}

void FrameThreads::drain() {
  const GstFlowReturn ret = push_all();
  if (ret != GST_FLOW_OK && drain_ret_ == GST_FLOW_OK)
    drain_ret_ = ret;
}

void FrameThreads::flush() {
  workers_.cancel_all();
  drain_ret_ = GST_FLOW_OK;
}

GstFlowReturn FrameThreads::generate_output(GstBaseTransformClass* parent,
                                            const TakeInputs& take_inputs, GstBuffer** outbuf) {
  GstBaseTransform* trans = trans_;
  *outbuf = nullptr;
  if (drain_ret_ != GST_FLOW_OK) { // A push while draining failed: say so now.
    const GstFlowReturn ret = drain_ret_;
    drain_ret_ = GST_FLOW_OK;
    gst_buffer_replace(&trans->queued_buf, nullptr);
    return ret;
  }

  if (GstBuffer* inbuf = trans->queued_buf) {
    trans->queued_buf = nullptr;
    FrameInputs in;
    if (!take_inputs(in)) {
      gst_buffer_unref(inbuf);
      return GST_FLOW_ERROR;
    }
    GstBuffer* buffer = nullptr; // The input made writable (copied only when shared).
    const GstFlowReturn ret = parent->prepare_output_buffer(trans, inbuf, &buffer);
    if (buffer != inbuf)
      gst_buffer_unref(inbuf);
    if (ret != GST_FLOW_OK || !buffer)
      return ret != GST_FLOW_OK ? ret : GST_FLOW_ERROR;
    workers_.submit(std::make_unique<FrameJob>(GST_ELEMENT(trans), attach_, buffer, std::move(in),
                                               trans->segment));
  }

  const bool busy = workers_.pending() >= static_cast<size_t>(workers_.threads());
  std::unique_ptr<OrderedWorkers::Job> job = workers_.take_oldest(busy);
  if (!job)
    return GST_FLOW_OK; // Nothing finished yet: the next input first.
  GstFlowReturn ret = GST_FLOW_OK;
  *outbuf = static_cast<FrameJob*>(job.get())->finish(ret);
  return ret;
}

void add_frame_thread_latency(GstObject* element, GstQuery* query, int threads,
                              const GstVideoInfo& info) {
  if (threads <= 1 || GST_VIDEO_INFO_FPS_N(&info) <= 0)
    return;
  const GstClockTime frame = gst_util_uint64_scale_int(GST_SECOND, GST_VIDEO_INFO_FPS_D(&info),
                                                       GST_VIDEO_INFO_FPS_N(&info));
  const GstClockTime added = frame * static_cast<GstClockTime>(threads - 1);
  gboolean live = FALSE;
  GstClockTime min = 0, max = GST_CLOCK_TIME_NONE;
  gst_query_parse_latency(query, &live, &min, &max);
  if (GST_CLOCK_TIME_IS_VALID(max))
    max += added;
  gst_query_set_latency(query, live, min + added, max);
  GST_DEBUG_OBJECT(element, "%d frame threads: latency + %" GST_TIME_FORMAT, threads,
                   GST_TIME_ARGS(added));
}

} // namespace gstpickdetect
