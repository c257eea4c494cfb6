#pragma once
/// @file The sweep's report page, `DIR/report.html`: one self-contained HTML file (inline CSS and
/// JavaScript, no external scripts, styles, fonts or URLs) that a person opens in a browser to
/// see how a sweep went. The C++ writes the skeleton, the data (summary.json embedded whole) and
/// the pictures' thumbnails; the page's script draws the header, the error histograms and the
/// sortable per-scene table.

#include <filesystem>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <string_view>

namespace hgrasp::app::sweep {

/// Width of a thumbnail in the report (px); the height keeps the picture's aspect.
constexpr int kThumbnailWidthPx = 160;
/// JPEG quality of the thumbnails (0..100).
constexpr int kThumbnailJpegQuality = 70;

/// The report page for `summary` (summary.json's schema: `sweep`, `totals`, `scenes[]`; any field
/// may be null or missing, and shows as "–").
///
/// The page holds `summary` unchanged as JSON in `<script type="application/json" id="data">`
/// (with `<`, `>` and `&` written as \u escapes, so no string can end the element), beside a
/// thumbnail of every picture a scene names in `pictures` (`segments`, `grasp`, `servo[]`, paths
/// relative to `sweep_dir`): a JPEG kThumbnailWidthPx wide, base64 in a data: URI, linked to the
/// full-size file by its relative path. Picture files that are missing or unreadable are skipped.
///
/// The page's script draws, into the skeleton: the sweep's stage, size, start and totals; a
/// histogram (inline SVG) of each error figure with its median and 95th percentile; and a table
/// of the scenes, worst first by `score` (higher is worse), sortable by any column, whose rows
/// open a detail row with the scene's facts and thumbnails. Errors while drawing are written into
/// `<pre id="errors">`; when it has drawn, the script sets `document.body.dataset.rendered = "1"`
/// and `document.body.dataset.rows` to the number of scene rows.
std::string ReportHtml(const nlohmann::json& summary, const std::filesystem::path& sweep_dir);

/// `bytes` in base64 (RFC 4648, standard alphabet, `=` padding, no line breaks).
std::string Base64(std::string_view bytes);

/// The picture at `path` shrunk (or grown) to `width_px` wide, aspect kept, as JPEG bytes of
/// quality kThumbnailJpegQuality; empty when the file is missing or is not a picture OpenCV reads.
/// @pre width_px > 0.
std::string JpegThumbnail(const std::filesystem::path& path, int width_px = kThumbnailWidthPx);

}  // namespace hgrasp::app::sweep
