// SPDX-License-Identifier: LGPL-2.1-or-later
#include "video-buffer.hpp"

#include <cstring>
#include <functional>

namespace pickdetect::tools {
namespace {

/// The padding and strides of Layout::Padded.
GstVideoAlignment padded_alignment() {
  GstVideoAlignment align;
  gst_video_alignment_reset(&align);
  align.padding_top = 3;
  align.padding_bottom = 5;
  align.padding_left = 6; // Must be a multiple of the chroma subsampling.
  align.padding_right = 10;
  for (guint p = 0; p < GST_VIDEO_MAX_PLANES; p++)
    align.stride_align[p] = 63; // Strides rounded up to 64 bytes.
  return align;
}

/// Row writer: plane, row, its bytes, how many.
using RowFill = std::function<void(guint plane, int y, guint8* row, int row_bytes)>;

/// A frame of `format` and `size` in `layout`, every row of every plane written by `fill`.
GstBuffer* make_frame(const char* format, cv::Size size, Layout layout, GstVideoInfo* info_out,
                      const RowFill& fill) {
  const GstVideoFormat f = gst_video_format_from_string(format);
  GstVideoInfo info;
  if (f == GST_VIDEO_FORMAT_UNKNOWN ||
      !gst_video_info_set_format(&info, f, static_cast<guint>(size.width),
                                 static_cast<guint>(size.height)))
    return nullptr;
  const GstVideoAlignment align = padded_alignment();
  GstBuffer* buffer = allocate_video_buffer(info, layout == Layout::Padded ? &align : nullptr);
  if (!buffer)
    return nullptr;
  GstVideoFrame frame;
  if (!gst_video_frame_map(&frame, &info, buffer, GST_MAP_WRITE)) {
    gst_buffer_unref(buffer);
    return nullptr;
  }
  for (guint p = 0; p < GST_VIDEO_FRAME_N_PLANES(&frame); p++) {
    // Row bytes and rows of the plane, from its first component.
    int comp[GST_VIDEO_MAX_COMPONENTS];
    gst_video_format_info_component(info.finfo, p, comp);
    const int rows = GST_VIDEO_FRAME_COMP_HEIGHT(&frame, comp[0]);
    const int row_bytes =
        GST_VIDEO_FRAME_COMP_WIDTH(&frame, comp[0]) * GST_VIDEO_FRAME_COMP_PSTRIDE(&frame, comp[0]);
    for (int y = 0; y < rows; y++)
      fill(p, y,
           static_cast<guint8*>(GST_VIDEO_FRAME_PLANE_DATA(&frame, p)) +
               static_cast<size_t>(y) * GST_VIDEO_FRAME_PLANE_STRIDE(&frame, p),
           row_bytes);
  }
  gst_video_frame_unmap(&frame);
  GST_BUFFER_PTS(buffer) = 0;
  GST_BUFFER_DURATION(buffer) = GST_SECOND / 30;
  if (info_out)
    *info_out = info;
  return buffer;
}

} // namespace

GstBuffer* converted_video_buffer(const cv::Mat& bgr, const char* format, Layout layout,
                                  GstVideoInfo* info_out) {
  GstVideoInfo in_info, out_info;
  GstBuffer* in = video_buffer(bgr, "BGR", Layout::Default, &in_info);
  // Filled by the converter below: the rows are left as they are.
  GstBuffer* out =
      in ? make_frame(format, bgr.size(), layout, &out_info, [](guint, int, guint8*, int) {})
         : nullptr;
  GstVideoConverter* converter =
      out ? gst_video_converter_new(&in_info, &out_info, nullptr) : nullptr;
  GstVideoFrame from, to;
  bool done = false;
  if (converter && gst_video_frame_map(&from, &in_info, in, GST_MAP_READ)) {
    if (gst_video_frame_map(&to, &out_info, out, GST_MAP_WRITE)) {
      gst_video_converter_frame(converter, &from, &to);
      gst_video_frame_unmap(&to);
      done = true;
    }
    gst_video_frame_unmap(&from);
  }
  if (converter)
    gst_video_converter_free(converter);
  if (in)
    gst_buffer_unref(in);
  if (!done) {
    if (out)
      gst_buffer_unref(out);
    return nullptr;
  }
  if (info_out)
    *info_out = out_info;
  return out;
}

std::string caps_string(const char* format, cv::Size size, int fps) {
  return "video/x-raw,format=" + std::string(format) + ",width=" + std::to_string(size.width) +
         ",height=" + std::to_string(size.height) + ",framerate=" + std::to_string(fps) + "/1";
}

GstBuffer* allocate_video_buffer(GstVideoInfo& info, const GstVideoAlignment* align) {
  if (align) {
    GstVideoAlignment a = *align;
    if (!gst_video_info_align(&info, &a))
      return nullptr;
  }
  GstBuffer* buffer = gst_buffer_new_allocate(nullptr, GST_VIDEO_INFO_SIZE(&info), nullptr);
  gst_buffer_memset(buffer, 0, kCanary, GST_VIDEO_INFO_SIZE(&info));
  if (align)
    gst_buffer_add_video_meta_full(buffer, GST_VIDEO_FRAME_FLAG_NONE, GST_VIDEO_INFO_FORMAT(&info),
                                   GST_VIDEO_INFO_WIDTH(&info), GST_VIDEO_INFO_HEIGHT(&info),
                                   GST_VIDEO_INFO_N_PLANES(&info), info.offset, info.stride);
  return buffer;
}

GstBuffer* video_buffer(const cv::Mat& picture, const char* format, Layout layout,
                        GstVideoInfo* info_out) {
  const GstVideoFormat f = gst_video_format_from_string(format);
  const GstVideoFormatInfo* finfo = gst_video_format_get_info(f);
  if (!finfo || picture.depth() != CV_8U || (picture.channels() != 1 && picture.channels() != 3))
    return nullptr;
  if (picture.channels() == 3 && f != GST_VIDEO_FORMAT_BGR)
    return converted_video_buffer(picture, format, layout, info_out);
  const bool rgb = GST_VIDEO_FORMAT_INFO_IS_RGB(finfo);
  const int pstride = GST_VIDEO_FORMAT_INFO_PSTRIDE(finfo, 0);
  const int alpha =
      GST_VIDEO_FORMAT_INFO_HAS_ALPHA(finfo) ? GST_VIDEO_FORMAT_INFO_POFFSET(finfo, 3) : -1;
  const bool copy = picture.channels() == 3 || !rgb || pstride == 1;
  return make_frame(format, picture.size(), layout, info_out,
                    [&](guint plane, int y, guint8* row, int row_bytes) {
                      if (plane > 0) { // Chroma: neutral.
                        std::memset(row, 128, static_cast<size_t>(row_bytes));
                      } else if (copy) {
                        std::memcpy(row, picture.ptr(y), picture.cols * picture.elemSize());
                      } else {
                        const guint8* grey = picture.ptr<guint8>(y);
                        for (int x = 0; x < picture.cols; x++) {
                          std::memset(row + x * pstride, grey[x], pstride);
                          if (alpha >= 0)
                            row[x * pstride + alpha] = 255;
                        }
                      }
                    });
}

GstBuffer* noise_video_buffer(const char* format, cv::Size size, Layout layout,
                              GstVideoInfo* info_out) {
  cv::RNG rng(static_cast<uint64>(size.width) * 7919 + size.height);
  return make_frame(format, size, layout, info_out, [&](guint, int, guint8* row, int row_bytes) {
    for (int x = 0; x < row_bytes; x++)
      row[x] = static_cast<guint8>(rng.uniform(0, 256));
  });
}

} // namespace pickdetect::tools
