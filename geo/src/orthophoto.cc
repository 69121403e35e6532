#include "skerry/geo/orthophoto.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <mutex>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <vector>

#include "gdal_support.h"
#include "skerry/core/input_error.h"

namespace skerry::geo {
namespace {

namespace fs = std::filesystem;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The CRS sidecars looked for next to an image, in this order: STEM.prj, STEM.wkt, STEM-srs.wkt.
constexpr const char* kCrsSidecarSuffixes[] = {".prj", ".wkt", "-srs.wkt"};

// The first sidecar that exists.
std::string FindCrsSidecar(const std::string& path) {
  const fs::path p(path);
  const fs::path stem = p.parent_path() / p.stem();
  for (const std::string suffix : kCrsSidecarSuffixes) {
    const fs::path candidate = stem.string() + suffix;
    std::error_code ec;
    if (fs::is_regular_file(candidate, ec)) return candidate.string();
  }
  return "";
}

// Band indices (1-based) for B, G, R: by colour interpretation, else bands 3, 2, 1.
void FindBgrBands(GDALDataset& dataset, int bgr[3]) {
  bgr[0] = 3;
  bgr[1] = 2;
  bgr[2] = 1;
  int found[3] = {0, 0, 0};
  for (int b = 1; b <= dataset.GetRasterCount(); ++b) {
    switch (dataset.GetRasterBand(b)->GetColorInterpretation()) {
      case GCI_BlueBand:
        found[0] = b;
        break;
      case GCI_GreenBand:
        found[1] = b;
        break;
      case GCI_RedBand:
        found[2] = b;
        break;
      default:
        break;
    }
  }
  if (found[0] && found[1] && found[2]) {
    for (int k = 0; k < 3; ++k) bgr[k] = found[k];
  }
}

// Channels of the image in memory: BGR for three or more bands or a palette, else grey.
int ImageChannels(GDALDataset& dataset) {
  if (dataset.GetRasterCount() >= 3) return 3;
  GDALRasterBand* first = dataset.GetRasterBand(1);
  const bool palette = first != nullptr && first->GetColorInterpretation() == GCI_PaletteIndex &&
                       first->GetColorTable() != nullptr;
  return palette ? 3 : 1;
}

// The bands read, in the order of the image's channels (B, G, R, or the one grey band).
struct ImageBands {
  std::vector<int> bands;
  bool all_bytes = true;
};

ImageBands UsedBands(GDALDataset& dataset, const std::string& path) {
  ImageBands use;
  if (dataset.GetRasterCount() < 1) throw InputError(path, 0, "bands", "the image has no bands");
  if (dataset.GetRasterCount() >= 3) {
    int bgr[3];
    FindBgrBands(dataset, bgr);
    use.bands.assign(bgr, bgr + 3);
  } else {
    use.bands = {1};
  }
  for (const int b : use.bands) {
    GDALRasterBand* band = dataset.GetRasterBand(b);
    const GDALDataType type = band->GetRasterDataType();
    if (GDALDataTypeIsComplex(type)) {
      throw InputError(path, 0, "bands",
                       "band " + std::to_string(b) + " holds complex numbers (" +
                           GDALGetDataTypeName(type) + "), not an image");
    }
    use.all_bytes = use.all_bytes && type == GDT_Byte;
  }
  GDALRasterBand* first = dataset.GetRasterBand(1);
  if (!use.all_bytes && use.bands.size() == 1 &&
      first->GetColorInterpretation() == GCI_PaletteIndex && first->GetColorTable() != nullptr) {
    throw InputError(path, 0, "bands",
                     std::string("a palette on ") +
                         GDALGetDataTypeName(first->GetRasterDataType()) +
                         " indices is not supported (only on 8-bit ones)");
  }
  return use;
}

// The pixels (x, y) of `window` (inside the image), 8-bit bands as they are: BGR, grey, or a
// palette's colours.
void ReadBytes(GDALDataset& dataset,
               const ImageBands& use,
               const std::string& path,
               const cv::Rect& window,
               cv::Mat& image) {
  const int w = window.width;
  const int h = window.height;
  if (use.bands.size() == 3) {
    int bgr[3] = {use.bands[0], use.bands[1], use.bands[2]};
    image.create(h, w, CV_8UC3);
    if (dataset.RasterIO(GF_Read, window.x, window.y, w, h, image.data, w, h, GDT_Byte, 3, bgr, 3,
                         static_cast<GSpacing>(image.step), 1, nullptr) != CE_None) {
      throw InputError(path, 0, "",
                       "cannot read the pixels" + internal::QuietGdalErrors::LastMessage());
    }
    return;
  }
  GDALRasterBand* first = dataset.GetRasterBand(1);
  cv::Mat gray(h, w, CV_8UC1);
  if (first->RasterIO(GF_Read, window.x, window.y, w, h, gray.data, w, h, GDT_Byte, 1,
                      static_cast<GSpacing>(gray.step), nullptr) != CE_None) {
    throw InputError(path, 0, "",
                     "cannot read the pixels" + internal::QuietGdalErrors::LastMessage());
  }
  const GDALColorTable* palette = first->GetColorTable();
  if (first->GetColorInterpretation() != GCI_PaletteIndex || palette == nullptr) {
    image = gray;
    return;
  }
  image.create(h, w, CV_8UC3);
  GDALColorEntry entries[256];
  for (int i = 0; i < 256; ++i) {
    entries[i] = {0, 0, 0, 255};
    if (i < palette->GetColorEntryCount()) palette->GetColorEntryAsRGB(i, &entries[i]);
  }
  for (int r = 0; r < h; ++r) {
    const std::uint8_t* in = gray.ptr<std::uint8_t>(r);
    cv::Vec3b* out = image.ptr<cv::Vec3b>(r);
    for (int c = 0; c < w; ++c) {
      const GDALColorEntry& e = entries[in[c]];
      out[c] = cv::Vec3b(static_cast<std::uint8_t>(e.c3), static_cast<std::uint8_t>(e.c2),
                         static_cast<std::uint8_t>(e.c1));
    }
  }
}

// Calls visit(first_row, rows, cells) for strips of kStripRows rows of `window` (inside the
// image) of the used bands read as float, pixel-interleaved: channel k of (row, col) at
// (row * window.width + col) * channels + k; rows and columns counted from the window's corner.
constexpr int kStripRows = 256;
template <typename Visit>
void ForEachFloatStrip(GDALDataset& dataset,
                       const ImageBands& use,
                       const std::string& path,
                       const cv::Rect& window,
                       Visit&& visit) {
  const int w = window.width;
  const int h = window.height;
  const int channels = static_cast<int>(use.bands.size());
  std::vector<float> strip(static_cast<size_t>(kStripRows) * w * channels);
  std::vector<int> bands = use.bands;
  for (int r0 = 0; r0 < h; r0 += kStripRows) {
    const int rows = std::min(kStripRows, h - r0);
    if (dataset.RasterIO(GF_Read, window.x, window.y + r0, w, rows, strip.data(), w, rows,
                         GDT_Float32, channels, bands.data(),
                         static_cast<GSpacing>(sizeof(float)) * channels,
                         static_cast<GSpacing>(sizeof(float)) * channels * w,
                         static_cast<GSpacing>(sizeof(float)), nullptr) != CE_None) {
      throw InputError(path, 0, "",
                       "cannot read the pixels" + internal::QuietGdalErrors::LastMessage());
    }
    visit(r0, rows, static_cast<const float*>(strip.data()));
  }
}

// Some used band has a mask beyond GDAL's "all valid" (RFC 15: a no-data value, an alpha band,
// a .msk file). With `nodata_read`, masks made of a no-data value only do not count: the caller
// compares the cells with it already (ReadStretched), and GDAL would read every cell again to
// make them.
bool HasGdalMask(GDALDataset& dataset, const ImageBands& use, bool nodata_read) {
  for (const int b : use.bands) {
    const int flags = dataset.GetRasterBand(b)->GetMaskFlags();
    if ((flags & GMF_ALL_VALID) != 0 || (nodata_read && flags == GMF_NODATA)) return false;
  }
  return true;
}

// Where GDAL's mask bands say the pixels of `window` (inside the image) hold data: 255 where at
// least one used band's mask is at least 128 (alpha: mostly opaque), else 0. Empty when
// HasGdalMask(nodata_read) is false (every cell valid).
cv::Mat ReadGdalMask(GDALDataset& dataset,
                     const ImageBands& use,
                     const std::string& path,
                     bool nodata_read,
                     const cv::Rect& window) {
  if (!HasGdalMask(dataset, use, nodata_read)) return {};
  const int w = window.width;
  const int h = window.height;
  cv::Mat valid(h, w, CV_8UC1, cv::Scalar(0));
  cv::Mat strip(kStripRows, w, CV_8UC1);
  bool per_dataset_read = false;
  for (const int b : use.bands) {
    GDALRasterBand* band = dataset.GetRasterBand(b);
    if (band->GetMaskFlags() & GMF_PER_DATASET) {
      if (per_dataset_read) continue;  // the same mask for every band
      per_dataset_read = true;
    }
    for (int r0 = 0; r0 < h; r0 += kStripRows) {
      const int rows = std::min(kStripRows, h - r0);
      if (band->GetMaskBand()->RasterIO(GF_Read, window.x, window.y + r0, w, rows, strip.data, w,
                                        rows, GDT_Byte, 1, static_cast<GSpacing>(strip.step),
                                        nullptr) != CE_None) {
        throw InputError(path, 0, "",
                         "cannot read the image's mask" + internal::QuietGdalErrors::LastMessage());
      }
      cv::Mat out = valid.rowRange(r0, r0 + rows);
      const cv::Mat in = strip.rowRange(0, rows) >= 128;
      cv::bitwise_or(out, in, out);
    }
  }
  return valid;
}

// The no-data value of each used band as the float GDAL converts it to (saturating outside
// float's range, like every other cell), NaN when a band declares none.
std::vector<double> FloatNoData(GDALDataset& dataset, const ImageBands& use) {
  std::vector<double> nodata(use.bands.size(), kNaN);
  for (size_t k = 0; k < use.bands.size(); ++k) {
    int has = 0;
    const double value = dataset.GetRasterBand(use.bands[k])->GetNoDataValue(&has);
    constexpr double kMaxFloat = std::numeric_limits<float>::max();
    if (has && !std::isnan(value)) {
      nodata[k] = static_cast<float>(std::clamp(value, -kMaxFloat, kMaxFloat));
    }
  }
  return nodata;
}

// Calls visit(v) for every cell of the used bands that is finite, not its band's no-data value,
// and (with `masked`) in a pixel where GDAL's mask bands say the image holds data (ReadGdalMask,
// read strip by strip alongside the cells: the whole image is never held).
template <typename Visit>
void ForEachValidCell(GDALDataset& dataset,
                      const ImageBands& use,
                      const std::string& path,
                      bool masked,
                      Visit&& visit) {
  const std::vector<double> nodata = FloatNoData(dataset, use);
  const size_t channels = use.bands.size();
  const int w = dataset.GetRasterXSize();
  const cv::Rect all(0, 0, w, dataset.GetRasterYSize());
  ForEachFloatStrip(dataset, use, path, all, [&](int r0, int rows, const float* cells) {
    const cv::Mat mask =
        masked ? ReadGdalMask(dataset, use, path, /*nodata_read=*/true, cv::Rect(0, r0, w, rows))
               : cv::Mat();
    for (int r = 0; r < rows; ++r) {
      const std::uint8_t* holds = mask.empty() ? nullptr : mask.ptr<std::uint8_t>(r);
      const float* in = cells + static_cast<size_t>(r) * w * channels;
      for (int c = 0; c < w; ++c) {
        if (holds != nullptr && holds[c] == 0) continue;
        for (size_t k = 0; k < channels; ++k) {
          const double v = in[static_cast<size_t>(c) * channels + k];
          if (std::isfinite(v) && v != nodata[k]) visit(v);
        }
      }
    }
  });
}

// GDAL's minimum and maximum count infinite cells and cells an alpha band or a .msk file
// masks: the extremes of the valid ones (ForEachValidCell). InputError when there is none.
void FiniteMinMax(GDALDataset& dataset,
                  const ImageBands& use,
                  const std::string& path,
                  bool masked,
                  double& lo,
                  double& hi) {
  lo = std::numeric_limits<double>::infinity();
  hi = -lo;
  ForEachValidCell(dataset, use, path, masked, [&](double v) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  });
  if (!(lo <= hi)) {
    throw InputError(path, 0, "bands",
                     "the image has no valid cell (all no-data, NaN, infinite or masked)");
  }
}

// The values a 16-bit, 32-bit or floating-point image maps to 0 and 255: the `clip` and
// 1 - `clip` quantiles of the valid cells of all used bands together (one mapping for every band
// keeps grey grey), from the exact minimum and maximum and a histogram of 65536 bins between
// them (at most one unit wide for 16-bit cells). No-data, NaN and infinite cells are not counted,
// nor (`masked`: GDAL's mask bands beyond no-data values, HasGdalMask) cells an alpha band or a
// .msk file masks: a mosaic's transparent border would otherwise pull the dark end of the stretch
// to its own value. GDAL's statistics see no-data values but not those masks, so with a mask the
// cells are read and counted here.
Eigen::Vector2d StretchRange(GDALDataset& dataset,
                             const ImageBands& use,
                             double clip,
                             const std::string& path,
                             bool masked) {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -lo;
  if (!masked) {
    for (const int b : use.bands) {
      double minmax[2];
      if (dataset.GetRasterBand(b)->ComputeRasterMinMax(FALSE, minmax) != CE_None) {
        throw InputError(path, 0, "bands",
                         "band " + std::to_string(b) + " has no valid cell (all no-data or NaN)" +
                             internal::QuietGdalErrors::LastMessage());
      }
      lo = std::min(lo, minmax[0]);
      hi = std::max(hi, minmax[1]);
    }
  }
  if (!(std::isfinite(lo) && std::isfinite(hi))) FiniteMinMax(dataset, use, path, masked, lo, hi);
  if (hi <= lo) return {lo, lo + 1.0};  // a constant image: everything is 0
  constexpr int kBins = 65536;
  std::vector<GUIntBig> total(kBins, 0);
  if (!masked) {
    std::vector<GUIntBig> counts(kBins);
    for (const int b : use.bands) {
      if (dataset.GetRasterBand(b)->GetHistogram(lo, hi, kBins, counts.data(), TRUE, FALSE, nullptr,
                                                 nullptr) != CE_None) {
        throw InputError(path, 0, "",
                         "cannot read the pixels" + internal::QuietGdalErrors::LastMessage());
      }
      for (int k = 0; k < kBins; ++k) total[k] += counts[k];
    }
  } else {
    const double per_bin = kBins / (hi - lo);
    ForEachValidCell(dataset, use, path, masked, [&](double v) {
      ++total[std::clamp(static_cast<int>((v - lo) * per_bin), 0, kBins - 1)];
    });
  }
  GUIntBig n = 0;
  for (const GUIntBig c : total) n += c;
  const double bin = (hi - lo) / kBins;
  // The value below which a fraction q of the cells lie, interpolated inside its bin.
  const auto quantile = [&](double q) {
    const double target = q * static_cast<double>(n);
    double below = 0.0;
    for (int k = 0; k < kBins; ++k) {
      const double c = static_cast<double>(total[k]);
      if (below + c >= target && c > 0) return lo + bin * (k + (target - below) / c);
      below += c;
    }
    return hi;
  };
  Eigen::Vector2d range(quantile(clip), quantile(1.0 - clip));
  if (range.y() <= range.x()) range = {lo, hi};
  return range;
}

// The used bands of `window` (inside the image) read as float in strips of rows and mapped
// linearly from `range` onto 0..255; no-data, NaN and infinite cells (a double beyond float's
// range) become 0. `holds_data` (CV_8UC1) is 0 where every channel is such a cell, else 255.
void ReadStretched(GDALDataset& dataset,
                   const ImageBands& use,
                   const Eigen::Vector2d& range,
                   const std::string& path,
                   const cv::Rect& window,
                   cv::Mat& image,
                   cv::Mat& holds_data) {
  const int w = window.width;
  const int h = window.height;
  const size_t channels = use.bands.size();
  image.create(h, w, channels == 3 ? CV_8UC3 : CV_8UC1);
  holds_data.create(h, w, CV_8UC1);
  const std::vector<double> nodata = FloatNoData(dataset, use);
  const double scale = 255.0 / (range.y() - range.x());
  ForEachFloatStrip(dataset, use, path, window, [&](int r0, int rows, const float* cells) {
    for (int r = 0; r < rows; ++r) {
      std::uint8_t* out = image.ptr<std::uint8_t>(r0 + r);
      std::uint8_t* has = holds_data.ptr<std::uint8_t>(r0 + r);
      const float* in = cells + static_cast<size_t>(r) * w * channels;
      for (int c = 0; c < w; ++c) {
        bool any = false;
        for (size_t k = 0; k < channels; ++k) {
          const size_t i = static_cast<size_t>(c) * channels + k;
          const double v = in[i];
          if (!std::isfinite(v) || v == nodata[k]) {
            out[i] = 0;
            continue;
          }
          any = true;
          const double scaled = std::clamp((v - range.x()) * scale, 0.0, 255.0);
          out[i] = static_cast<std::uint8_t>(scaled + 0.5);
        }
        has[c] = any ? 255 : 0;
      }
    }
  });
}

// The pixels of `window` (inside the image) as the image holds them (Orthophoto::image(),
// valid_mask()): 8-bit bands as they are, deeper ones stretched from `range`; `valid` empty when
// every pixel of the window holds data, else 0 where none does, and the image 0 there.
void ReadPixels(GDALDataset& dataset,
                const ImageBands& use,
                const Eigen::Vector2d& range,
                const std::string& path,
                const cv::Rect& window,
                cv::Mat& image,
                cv::Mat& valid) {
  internal::QuietGdalErrors quiet;
  if (use.all_bytes) {
    ReadBytes(dataset, use, path, window, image);
    valid = ReadGdalMask(dataset, use, path, /*nodata_read=*/false, window);
  } else {
    valid = ReadGdalMask(dataset, use, path, /*nodata_read=*/true, window);
    cv::Mat holds_data;  // where some band is finite and not no-data
    ReadStretched(dataset, use, range, path, window, image, holds_data);
    if (valid.empty()) {
      valid = holds_data;
    } else {
      cv::bitwise_and(valid, holds_data, valid);
    }
  }
  if (valid.empty()) return;
  if (cv::countNonZero(valid) == static_cast<int>(valid.total())) {
    valid.release();  // every cell holds data
  } else {
    image.setTo(cv::Scalar::all(0), valid == 0);
  }
}

// Rows of `image` (CV_8UC1 or CV_8UC3) and `valid` (empty: every pixel holds data) reduced
// `factor` times along each axis into the rows of `out` and `out_valid` from `out_row0`
// (Orthophoto::Pixels(window, factor)): blocks of factor x factor pixels, cut short at the right
// and bottom edges, become the rounded mean of their pixels that hold data, and hold data when
// at least half of them do. Strips that start on a block's first row give the whole window's
// blocks.
void ReduceBlocks(const cv::Mat& image,
                  const cv::Mat& valid,
                  int factor,
                  int out_row0,
                  cv::Mat& out,
                  cv::Mat& out_valid) {
  const int channels = image.channels();
  const int out_w = out.cols;
  std::vector<std::uint64_t> sum(static_cast<size_t>(out_w) * channels);
  std::vector<std::uint32_t> count(static_cast<size_t>(out_w));
  std::vector<std::uint32_t> total(static_cast<size_t>(out_w));
  for (int r0 = 0; r0 < image.rows; r0 += factor) {
    std::fill(sum.begin(), sum.end(), 0);
    std::fill(count.begin(), count.end(), 0);
    std::fill(total.begin(), total.end(), 0);
    for (int r = r0; r < std::min(r0 + factor, image.rows); ++r) {
      const std::uint8_t* in = image.ptr<std::uint8_t>(r);
      const std::uint8_t* holds = valid.empty() ? nullptr : valid.ptr<std::uint8_t>(r);
      for (int c = 0; c < image.cols; ++c) {
        const size_t i = static_cast<size_t>(c / factor);
        ++total[i];
        if (holds != nullptr && holds[c] == 0) continue;
        ++count[i];
        for (int k = 0; k < channels; ++k) {
          sum[i * channels + k] += in[static_cast<size_t>(c) * channels + k];
        }
      }
    }
    std::uint8_t* o = out.ptr<std::uint8_t>(out_row0 + r0 / factor);
    std::uint8_t* o_valid = out_valid.ptr<std::uint8_t>(out_row0 + r0 / factor);
    for (size_t i = 0; i < static_cast<size_t>(out_w); ++i) {
      const bool holds = count[i] > 0 && 2 * count[i] >= total[i];
      o_valid[i] = holds ? 255 : 0;
      for (int k = 0; k < channels; ++k) {
        o[i * channels + k] =
            holds ? static_cast<std::uint8_t>((sum[i * channels + k] + count[i] / 2) / count[i])
                  : 0;
      }
    }
  }
}

// A read from disk of at least this many pixels leaves GDAL's block cache empty (GDALDataset::
// FlushCache): a window is read once, into memory of its own, and the cache (5 % of the machine's
// memory by default) would otherwise hold its blocks a second time. Small reads (HoldsData) keep
// their blocks for the next.
constexpr std::int64_t kFlushPixels = std::int64_t{1} << 20;

// The pixel (u, v) lies inside the image's outer edge.
bool InsideImage(const Eigen::Vector2d& uv, int width, int height) {
  return uv.x() >= -0.5 && uv.x() <= width - 0.5 && uv.y() >= -0.5 && uv.y() <= height - 0.5;
}

}  // namespace

struct Orthophoto::Impl {
  Impl(const std::string& p, const LocalFrame& f) : path(p), frame(f) {}

  std::string path;
  LocalFrame frame;
  cv::Mat image;
  double gt[6] = {0, 1, 0, 0, 0, 1};
  double inv_gt[6] = {0, 1, 0, 0, 0, 1};
  std::string crs_wkt;
  std::string crs_source;
  std::unique_ptr<internal::CrsToWgs84> transform;
  std::vector<Eigen::Vector2d> footprint;
  Eigen::AlignedBox2d box;
  Eigen::Vector2d gsd = Eigen::Vector2d::Zero();
  Eigen::Vector2d value_range = {0.0, 255.0};
  cv::Mat valid;  // empty: every cell holds data
  double valid_share = 1.0;
  int width = 0, height = 0;
  // OrthophotoOptions::on_disk: the open file, read by window under the mutex (a GDAL dataset
  // is not thread-safe), with at most max_pixels per window.
  internal::GdalDatasetPtr dataset;
  ImageBands use;
  std::int64_t max_pixels = 0;
  int channels = 1;  // of image(): 3 (BGR) or 1
  std::mutex read_mutex;
};

Orthophoto::Orthophoto(const std::string& path,
                       const LocalFrame& frame,
                       const OrthophotoOptions& options)
    : impl_(std::make_unique<Impl>(path, frame)) {
  Impl& d = *impl_;
  internal::GdalDatasetPtr dataset = internal::OpenRaster(path);
  const int w = dataset->GetRasterXSize();
  const int h = dataset->GetRasterYSize();
  if (!(options.clip_fraction >= 0.0 && options.clip_fraction < 0.5)) {
    throw std::invalid_argument("OrthophotoOptions::clip_fraction must be in [0, 0.5)");
  }
  d.width = w;
  d.height = h;
  if (options.max_pixels < 1) {
    throw std::invalid_argument("OrthophotoOptions::max_pixels must be at least 1");
  }
  d.max_pixels = options.max_pixels;
  d.channels = ImageChannels(*dataset);
  if (!options.on_disk) {
    internal::RequireRasterFits(*dataset, options.max_pixels, ImageChannels(*dataset),
                                "OrthophotoOptions::max_pixels", path);
  }

  // Georeferencing: GDAL's (GeoTIFF tags or a world file it found), else a world file read by
  // GDALReadWorldFile under the extensions GDAL itself does not try for every driver.
  if (dataset->GetGeoTransform(d.gt) != CE_None) {
    bool found = false;
    for (const char* ext : {"wld", "jgw", "pgw", "tfw", "gfw", "jpgw", "pngw"}) {
      if (GDALReadWorldFile(path.c_str(), ext, d.gt)) {
        found = true;
        break;
      }
    }
    if (!found) {
      throw InputError(path, 0, "geotransform",
                       "no georeferencing: neither GeoTIFF tags nor a world file (.wld, .jgw, "
                       ".pgw, .tfw) next to the image");
    }
  }
  if (!GDALInvGeoTransform(d.gt, d.inv_gt)) {
    throw InputError(path, 0, "geotransform", "degenerate geotransform / world file");
  }

  OGRSpatialReference crs;
  if (!options.crs.empty()) {
    crs = internal::ParseCrs(options.crs, path, "crs");
    d.crs_source = "override";
  } else if (const OGRSpatialReference* own = dataset->GetSpatialRef();
             own != nullptr && !own->IsEmpty()) {
    crs = internal::NormaliseCrs(*own, path);
    d.crs_source = "file";
  } else if (const std::string sidecar = FindCrsSidecar(path); !sidecar.empty()) {
    crs = internal::ParseCrs(sidecar, path, "crs");
    d.crs_source = "sidecar " + sidecar;
  } else {
    const std::string stem = fs::path(path).stem().string();
    std::string sidecars;
    for (const char* suffix : kCrsSidecarSuffixes) {
      sidecars += (sidecars.empty()                   ? ""
                   : suffix == kCrsSidecarSuffixes[2] ? " or "
                                                      : ", ") +
                  stem + suffix;
    }
    throw InputError(path, 0, "crs",
                     "the image has no CRS: none in the file, no sidecar (" + sidecars +
                         ") next to it, and none given; give one (\"EPSG:2992\", WKT, a PROJ "
                         "string or a .prj / .wkt file) as " +
                         options.crs_given_as);
  }
  d.crs_wkt = internal::CrsWkt(crs);
  d.transform = std::make_unique<internal::CrsToWgs84>(crs, path);

  // Pixels: the stretch of deeper cells is the whole image's (read strip by strip); the pixels
  // are read now, or by window when they stay on disk.
  const ImageBands use = UsedBands(*dataset, path);
  internal::QuietGdalErrors quiet;
  if (!use.all_bytes) {
    d.value_range = StretchRange(*dataset, use, options.clip_fraction, path,
                                 HasGdalMask(*dataset, use, /*nodata_read=*/true));
  }
  if (options.on_disk) {
    d.use = use;
    d.valid_share = kNaN;
  } else {
    ReadPixels(*dataset, use, d.value_range, path, cv::Rect(0, 0, w, h), d.image, d.valid);
    if (!d.valid.empty()) {
      d.valid_share =
          static_cast<double>(cv::countNonZero(d.valid)) / static_cast<double>(d.valid.total());
    }
  }

  // Footprint: the outer edge, 16 points per side, counter-clockwise in ENU for a north-up map
  // (top-left, bottom-left, bottom-right, top-right).
  constexpr int kSteps = 16;
  const double h0 = d.frame.origin().height_m;
  const double u_lo = -0.5;
  const double u_hi = w - 0.5;
  const double v_lo = -0.5;
  const double v_hi = h - 0.5;
  for (int side = 0; side < 4; ++side) {
    for (int k = 0; k < kSteps; ++k) {
      const double t = static_cast<double>(k) / kSteps;
      const double u[4] = {u_lo, u_lo + t * (u_hi - u_lo), u_hi, u_hi - t * (u_hi - u_lo)};
      const double v[4] = {v_lo + t * (v_hi - v_lo), v_hi, v_hi - t * (v_hi - v_lo), v_lo};
      const Eigen::Vector2d p = PixelToEnu(u[side], v[side], h0).head<2>();
      d.footprint.push_back(p);
      d.box.extend(p);
    }
  }
  const double uc = 0.5 * (w - 1);
  const double vc = 0.5 * (h - 1);
  const Eigen::Vector3d pc = PixelToEnu(uc, vc, 0.0);
  d.gsd = {(PixelToEnu(uc + 1, vc, 0.0) - pc).norm(), (PixelToEnu(uc, vc + 1, 0.0) - pc).norm()};
  if (options.on_disk) {
    dataset->FlushCache();  // the blocks the stretch read
    d.dataset = std::move(dataset);
  }
}

Orthophoto::~Orthophoto() = default;
Orthophoto::Orthophoto(Orthophoto&&) noexcept = default;
Orthophoto& Orthophoto::operator=(Orthophoto&&) noexcept = default;

const cv::Mat& Orthophoto::image() const { return impl_->image; }
const Eigen::Vector2d& Orthophoto::value_range() const { return impl_->value_range; }
const cv::Mat& Orthophoto::valid_mask() const { return impl_->valid; }
double Orthophoto::valid_share() const { return impl_->valid_share; }
int Orthophoto::width() const { return impl_->width; }
int Orthophoto::height() const { return impl_->height; }
bool Orthophoto::on_disk() const { return impl_->dataset != nullptr; }

OrthophotoPixels Orthophoto::Pixels(const cv::Rect& window) const {
  const Impl& d = *impl_;
  OrthophotoPixels out;
  out.rect = window & cv::Rect(0, 0, d.width, d.height);
  if (out.rect.empty()) return out;
  if (!on_disk()) {
    out.image = d.image(out.rect);
    if (!d.valid.empty()) out.valid = d.valid(out.rect);
    return out;
  }
  const std::int64_t pixels = std::int64_t{out.rect.width} * out.rect.height;
  if (pixels > d.max_pixels) {
    throw InputError(d.path, 0, "size",
                     "a window of " + std::to_string(out.rect.width) + " x " +
                         std::to_string(out.rect.height) +
                         " pixels is more than OrthophotoOptions::max_pixels (" +
                         std::to_string(d.max_pixels) + ")");
  }
  std::lock_guard<std::mutex> lock(impl_->read_mutex);
  ReadPixels(*d.dataset, d.use, d.value_range, d.path, out.rect, out.image, out.valid);
  if (pixels >= kFlushPixels) d.dataset->FlushCache();
  return out;
}

OrthophotoPixels Orthophoto::Pixels(const cv::Rect& window, int factor) const {
  if (factor < 1) throw std::invalid_argument("Orthophoto::Pixels: factor must be at least 1");
  if (factor == 1) return Pixels(window);
  const Impl& d = *impl_;
  OrthophotoPixels out;
  out.factor = factor;
  out.rect = window & cv::Rect(0, 0, d.width, d.height);
  if (out.rect.empty()) return out;
  const int w = (out.rect.width + factor - 1) / factor;
  const int h = (out.rect.height + factor - 1) / factor;
  if (on_disk() && std::int64_t{w} * h > d.max_pixels) {
    throw InputError(d.path, 0, "size",
                     "a window of " + std::to_string(out.rect.width) + " x " +
                         std::to_string(out.rect.height) + " pixels reduced " +
                         std::to_string(factor) + " times is " + std::to_string(w) + " x " +
                         std::to_string(h) + ", more than OrthophotoOptions::max_pixels (" +
                         std::to_string(d.max_pixels) + ")");
  }
  out.image.create(h, w, CV_8UC(d.channels));
  out.valid.create(h, w, CV_8UC1);
  if (!on_disk()) {
    ReduceBlocks(d.image(out.rect), d.valid.empty() ? cv::Mat() : d.valid(out.rect), factor, 0,
                 out.image, out.valid);
  } else {
    // Strips of whole blocks of at most 4 million pixels and max_pixels (or one row of blocks).
    constexpr std::int64_t kStripPixels = std::int64_t{1} << 22;
    const int rows =
        factor *
        static_cast<int>(std::max<std::int64_t>(
            1, std::min(kStripPixels, d.max_pixels) / (std::int64_t{factor} * out.rect.width)));
    std::lock_guard<std::mutex> lock(impl_->read_mutex);
    for (int r0 = 0; r0 < out.rect.height; r0 += rows) {
      const cv::Rect strip(out.rect.x, out.rect.y + r0, out.rect.width,
                           std::min(rows, out.rect.height - r0));
      cv::Mat image, valid;
      ReadPixels(*d.dataset, d.use, d.value_range, d.path, strip, image, valid);
      ReduceBlocks(image, valid, factor, r0 / factor, out.image, out.valid);
      d.dataset->FlushCache();
    }
  }
  if (cv::countNonZero(out.valid) == static_cast<int>(out.valid.total())) out.valid.release();
  return out;
}

Eigen::Vector3d Orthophoto::PixelToEnu(double u, double v, double height_m) const {
  double x = 0.0;
  double y = 0.0;
  GDALApplyGeoTransform(impl_->gt, u + 0.5, v + 0.5, &x, &y);
  if (impl_->transform->ToLonLat(&x, &y, 1) != 0) {
    throw std::runtime_error("Orthophoto::PixelToEnu: pixel (" + std::to_string(u) + ", " +
                             std::to_string(v) + ") of " + impl_->path +
                             " cannot be placed on WGS84");
  }
  return impl_->frame.ToEnu(y, x, height_m);
}

Eigen::Vector2d Orthophoto::EnuToPixel(const Eigen::Vector3d& p_w) const {
  const Eigen::Vector3d llh = impl_->frame.ToGeodetic(p_w);
  double x = llh.y();
  double y = llh.x();
  if (impl_->transform->FromLonLat(&x, &y, 1) != 0) return {kNaN, kNaN};
  double px = 0.0;
  double py = 0.0;
  GDALApplyGeoTransform(impl_->inv_gt, x, y, &px, &py);
  return {px - 0.5, py - 0.5};
}

bool Orthophoto::Covers(const Eigen::Vector3d& p_w) const {
  return InsideImage(EnuToPixel(p_w), width(), height());
}

bool Orthophoto::HoldsData(const Eigen::Vector3d& p_w) const {
  const Eigen::Vector2d uv = EnuToPixel(p_w);
  if (!InsideImage(uv, width(), height())) return false;
  const int c = std::clamp(static_cast<int>(std::lround(uv.x())), 0, width() - 1);
  const int r = std::clamp(static_cast<int>(std::lround(uv.y())), 0, height() - 1);
  const OrthophotoPixels pixel = Pixels(cv::Rect(c, r, 1, 1));
  return pixel.valid.empty() || pixel.valid.at<std::uint8_t>(0, 0) != 0;
}

const std::vector<Eigen::Vector2d>& Orthophoto::footprint_enu() const { return impl_->footprint; }
const Eigen::AlignedBox2d& Orthophoto::footprint_box_enu() const { return impl_->box; }
Eigen::Vector2d Orthophoto::gsd_m() const { return impl_->gsd; }
double Orthophoto::ground_sample_distance_m() const {
  return 0.5 * (impl_->gsd.x() + impl_->gsd.y());
}
const std::string& Orthophoto::path() const { return impl_->path; }
const std::string& Orthophoto::crs_wkt() const { return impl_->crs_wkt; }
const std::string& Orthophoto::crs_source() const { return impl_->crs_source; }
const LocalFrame& Orthophoto::frame() const { return impl_->frame; }

}  // namespace skerry::geo
