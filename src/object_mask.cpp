// SPDX-License-Identifier: LGPL-2.1-or-later
// A model picture continued beyond its object, for its features.
#include "object_mask.hpp"

#include <opencv2/imgproc.hpp>

#include <vector>

namespace pickdetect::detail {

cv::Mat continue_object(const cv::Mat& picture, const cv::Mat& mask) {
  CV_Assert(picture.type() == CV_8UC1);
  if (mask.empty() || cv::countNonZero(mask) == mask.rows * mask.cols)
    return picture;
  CV_Assert(mask.type() == CV_8UC1 && mask.size() == picture.size());
  // The distance transform labels each pixel with the nearest zero pixel of its input, the
  // object's pixels here, numbered from 1 in raster order, the order findNonZero lists them.
  const cv::Mat outside = mask == 0;
  cv::Mat distance, labels;
  cv::distanceTransform(outside, distance, labels, cv::DIST_L2, cv::DIST_MASK_5,
                        cv::DIST_LABEL_PIXEL);
  std::vector<cv::Point> object;
  cv::findNonZero(mask, object);
  cv::Mat out = picture.clone();
  for (int y = 0; y < out.rows; ++y) {
    const uchar* in = outside.ptr<uchar>(y);
    const int* label = labels.ptr<int>(y);
    uchar* row = out.ptr<uchar>(y);
    for (int x = 0; x < out.cols; ++x)
      if (in[x]) {
        const int k = label[x] - 1;
        if (k >= 0 && k < static_cast<int>(object.size()))
          row[x] = picture.at<uchar>(object[static_cast<size_t>(k)]);
      }
  }
  return out;
}

} // namespace pickdetect::detail
