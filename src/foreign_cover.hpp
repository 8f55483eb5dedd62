// SPDX-License-Identifier: LGPL-2.1-or-later
// Internal to the core: something that is no instance lying on one (a package of another kind,
// a bag, a hand), seen in the frame's pixels.
#pragma once

#include <pickdetect/detector.hpp>
#include <pickdetect/model.hpp>

#include <opencv2/core.hpp>

#include <vector>

namespace pickdetect::detail {

/// Side of the square cells the instance is compared in, in frame pixels.
constexpr int kCoverCell = 12;
/// A cell is compared only where the model's picture has texture there (standard deviation
/// of its band-passed grey levels at least this); the frame is textured there (at least the
/// second figure) or flat (a highlight that washed the print out, or a plain surface).
constexpr double kMinCellTexture = 8.0;
constexpr double kMinFrameTexture = 5.0;
/// A textured frame cell correlating this little with the model's picture carried there shows
/// something else.
constexpr double kMaxForeignCorrelation = 0.3;
/// A flat frame cell shows a plain surface lying on the print when the print, with as much of
/// its detail as the frame keeps where the print is seen (the median over the matching cells:
/// blur, exposure), would show at least kFlatCoverDetail times the flatness threshold there,
/// the frame shows at most kFlatCoverShare of that, and the cell is no highlight: no more than
/// kGlareLevels of the model's grey levels brighter than the print in the frame's light, or of
/// a clear colour (may_be_glare).
constexpr double kFlatCoverDetail = 2.0;
constexpr double kFlatCoverShare = 0.25;
constexpr double kGlareLevels = 30.0;

/// Where the model's picture is too plain to compare (under kMinCellTexture), a frame cell with
/// at least kMinDetailOverPlain of band-passed detail, and at least kDetailOverPlainTimes the
/// detail the frame keeps of the picture's own faint texture there (the frame may be sharper
/// than the picture), shows something else: a textured object lying on a plain part of the
/// print. A threshold of 8 also flagged an uncovered box of a synthetic cover set, 10 did not
/// (docs/accuracy.md).
constexpr double kMinDetailOverPlain = 10.0;
constexpr double kDetailOverPlainTimes = 3.0;

/// An instance counts as covered when a connected group of cells that do not show its print holds
/// at least kMinForeignCells cells that show something else, or at least kMinForeignInGroup
/// such cells among kMinMixedGroupCells or more (the others flat where the print would show: a
/// cover seen through motion blur is partly flat, partly smeared texture; or flat and lighter
/// than the print, as a highlight or a light lid is: a lid's sharp rim shows something else
/// around them, a highlight fades into the print). Groups of noise,
/// glare, blur and a touching neighbour's edge on uncovered instances stayed smaller on the
/// development sets, the README's synthetic ones and docs/hard-sets.md's (4 cells with 3 that
/// show something else were a packed box's blurred edge). A group also counts, whatever its
/// size, when two of its cells that show another colour than the print's (CellLook::other_colour,
/// below) lie side by side: on the uncovered instances of the development sets, the cover sets
/// and the real tote no two such cells did (docs/accuracy.md, "In colour"), and a plain object
/// of another colour too small for the groups above (about two cells across) is told by its
/// colour.
constexpr int kMinForeignCells = 4;
constexpr int kMinForeignInGroup = 3;
constexpr int kMinMixedGroupCells = 5;

/// Colour, where both the frame and the model's picture have it (compare_cells' `colour`): a
/// cell shows something else where its hue is off the print's by more than kMaxHueTurn degrees,
/// both holding at least kMinCellSaturation of colour (saturation: the channels' spread over
/// the largest), or where one is grey (under kGreySaturation) and the other holds at least
/// kClearSaturation, the grey one being the print or darker than the print (grey and as light
/// or lighter is a highlight washing the print out, or a white object: they cannot be told
/// apart). Cells darker than kMinColourLevel (mean of the three channels) on either side tell
/// nothing. The frame's channels are first scaled to the print's, by their medians over the
/// cells (the light's colour and gain). On the development sets, which light the frame at random,
/// no uncovered instance had two such cells side by side; covers of another colour over plain
/// print, which the grey comparison cannot see, made groups of 4-85 (docs/accuracy.md).
constexpr double kMaxHueTurn = 45.0;
constexpr double kMinCellSaturation = 0.25;
constexpr double kGreySaturation = 0.08;
constexpr double kClearSaturation = 0.4;
constexpr double kMinColourLevel = 20.0;

/// One cell's figures: band-passed detail (standard deviations), correlation, grey levels.
struct CellLook {
  bool compared = false; ///< Enough pixels, and the model's picture has texture there.
  /// Enough pixels, the model's picture plain there, and the frame shows detail
  /// (kMinDetailOverPlain).
  bool detail_over_plain = false;
  double detail_f = 0, detail_m = 0, correlation = 0, level_f = 0, level_m = 0;
  /// Enough pixels, and the frame's colour there is another than the print's (see kMaxHueTurn);
  /// only when compare_cells is given the frame's colour.
  bool other_colour = false;
  /// Compared, and the frame's colour there is clear (saturation at least kClearSaturation, as
  /// light as kMinColourLevel), whatever the picture's colour; only when compare_cells is given
  /// the frame's colour.
  bool clear_colour = false;
};

/// The instance's print, carried into the frame by its homography, compared with the frame
/// cell by cell (kCoverCell frame pixels, row by row).
struct CellComparison {
  /// Cell (r, c) covers frame pixels origin + kCoverCell * (c, r) to kCoverCell further.
  cv::Point origin;
  int rows = 0, columns = 0;
  std::vector<CellLook> looks;
  /// Cells where the frame shows the print (shows_print).
  int print_cells = 0;
  /// Medians over those cells: the frame's detail over the picture's (blur), and its grey
  /// levels over the picture's (exposure).
  double detail_kept = 0, light = 0;
};

/// The comparison behind foreign_cover_cells (see there): cells outside the frame, outside the
/// model's mask, near the edge of what is seen of it, under one of `above` or clipped are not
/// compared. A non-empty `within` (frame pixels) limits the comparison to that rectangle. With
/// `colour` (the frame in BGR, CV_8UC3 of the grey frame's size) and a model picture in colour,
/// each cell's colour is compared too (CellLook::other_colour). With a `motion_blur` of the frame
/// (Settings::motion_blur_x, motion_blur_y) of kLeastBlurPx or more, the picture is compared as the
/// frame shows it: blurred the same way (which cells are compared is still told by the picture's
/// own texture: where the blur leaves a textured print plain, a flat cell denies nothing);
/// without one, both pictures are band-passed over the object's own pixels (the model's mask
/// less `above`), so that what lies beside the object does not reach into its rim.
CellComparison compare_cells(const Instance& inst, const Model& model, const cv::Mat& grey,
                             const std::vector<const Instance*>& above,
                             const cv::Rect& within = cv::Rect(), const cv::Mat& colour = cv::Mat(),
                             const cv::Point2f& motion_blur = cv::Point2f());

/// Whether a cell shows the print: compared, textured in the frame, and correlating at
/// kMaxForeignCorrelation or more with the picture carried there.
bool shows_print(const CellLook& look);

/// Whether a compared cell may be a highlight washing the print out: brighter than the print by
/// more than kGlareLevels of the model's grey levels in the frame's light `light`, and not of a
/// clear colour. A highlight takes the light's colour, near white, whatever the print's; a
/// plain surface of clear colour brighter than the print is something lying on it (with a grey
/// model picture the colour comparison cannot tell it). White surfaces and highlights cannot be
/// told apart.
bool may_be_glare(const CellLook& look, double light);

/// Whether a compared cell of `cmp` shows something other than the print: textured and
/// correlating under kMaxForeignCorrelation, or flat where the print, with as much of its detail
/// as the frame keeps where it is seen, would show clearly and no highlight washes it out
/// (kFlatCoverDetail, kFlatCoverShare, may_be_glare). A flat cell in a dim or blurred frame,
/// where the print keeps little detail anywhere, denies nothing.
bool denies_print(const CellLook& look, const CellComparison& cmp);

/// The largest 4-connected group of cells where the frame does not show the instance's print,
/// among the groups that show enough of something else (kMinForeignCells; 0 when none does): the
/// model's picture, carried into the frame by the instance's homography, and the frame are
/// compared cell by cell (normalised cross-correlation at half size, through a band-pass that
/// leaves out light and blur, taken over the object's own pixels on a frame without motion
/// blur: what lies beside the object does not reach into its rim). A cell shows something else
/// where it correlates under kMaxForeignCorrelation, where it is flat though the print would show
/// clear detail there and it is no highlight (kFlatCoverDetail), or where it shows texture on a
/// plain part of the print (kMinDetailOverPlain); a flat cell does not show the print and joins the
/// group around it (a highlight's too, though it shows nothing else itself). Cells outside the
/// frame, outside the model's mask, near the edge of what is seen of it, or under one of `above`
/// (instances lying on this one) are not compared. Scattered single cells come from noise and
/// glare; an object lying on the instance leaves a connected group. `grey`: the frame, CV_8UC1;
/// `colour`, if not empty, the frame in BGR: a cell whose colour is another than the print's
/// (CellLook::other_colour) also shows something else, wherever the print is, plain or not.
/// `motion_blur`: the frame's, as compare_cells takes it.
int foreign_cover_cells(const Instance& inst, const Model& model, const cv::Mat& grey,
                        const std::vector<const Instance*>& above,
                        const cv::Mat& colour = cv::Mat(),
                        const cv::Point2f& motion_blur = cv::Point2f());

} // namespace pickdetect::detail
