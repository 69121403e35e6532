// Orthophoto on the Autzen aerial image (JPEG + world file + WKT sidecar, NAD83(HARN) Oregon
// Lambert in international feet): pixel <-> ENU, ground sample distance, the Lambert grid's
// rotation, band order, and every way of giving it a CRS and georeferencing.

#include "skerry/geo/orthophoto.h"

#include <gdal_priv.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <random>

#include "geo/geo_test_util.h"

namespace skerry::geo {
namespace {

namespace fs = std::filesystem;
using testing::ExpectInputError;
using testing::FreshDir;
using testing::kData;

const std::string kAutzenDir = kData + "/autzen";
const std::string kAutzenJpg = kAutzenDir + "/autzen.jpg";

constexpr double kDeg = M_PI / 180.0;

// An ENU frame at the image centre, 100 m ellipsoidal (the ground there is ~110 m).
LocalFrame AutzenFrame() {
  const Orthophoto rough(kAutzenJpg, LocalFrame({44.05, -123.07, 100.0}));
  const Eigen::Vector3d llh = rough.frame().ToGeodetic(
      rough.PixelToEnu(0.5 * (rough.width() - 1), 0.5 * (rough.height() - 1), 100.0));
  return LocalFrame({llh.x(), llh.y(), 100.0});
}

// Lambert conformal conic (2 standard parallels) on the GRS80 ellipsoid: the cone constant n
// and the scale factor k at latitude phi (Snyder, Map Projections - A Working Manual, 15-1..15-9).
struct Lambert {
  double e = std::sqrt(0.00669438002290);
  double M(double phi) const {
    return std::cos(phi) / std::sqrt(1 - e * e * std::sin(phi) * std::sin(phi));
  }
  double T(double phi) const {
    const double s = e * std::sin(phi);
    return std::tan(M_PI / 4 - phi / 2) / std::pow((1 - s) / (1 + s), e / 2);
  }
  double phi1 = 43.0 * kDeg;
  double phi2 = 45.5 * kDeg;
  double n() const {
    return (std::log(M(phi1)) - std::log(M(phi2))) / (std::log(T(phi1)) - std::log(T(phi2)));
  }
  double k(double phi) const { return M(phi1) * std::pow(T(phi) / T(phi1), n()) / M(phi); }
};

TEST(AutzenOrthophoto, PixelToEnuToPixelRoundTripsBelowAMicropixel) {
  SKERRY_SKIP_WITHOUT(kAutzenJpg);
  const Orthophoto ortho(kAutzenJpg, AutzenFrame());
  EXPECT_EQ(ortho.width(), 3248);
  EXPECT_EQ(ortho.height(), 4385);
  EXPECT_EQ(ortho.crs_source(), "sidecar " + kAutzenDir + "/autzen-srs.wkt");
  // The centre pixel is the origin (that is how the frame was built).
  EXPECT_LT(ortho.PixelToEnu(1623.5, 2192.0, 100.0).norm(), 1e-6);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.5, ortho.width() - 0.5);
  std::uniform_real_distribution<double> v(-0.5, ortho.height() - 0.5);
  std::uniform_real_distribution<double> h(-50.0, 500.0);
  double worst = 0.0;
  for (int k = 0; k < 5000; ++k) {
    const Eigen::Vector2d uv(u(rng), v(rng));
    const Eigen::Vector2d back = ortho.EnuToPixel(ortho.PixelToEnu(uv.x(), uv.y(), h(rng)));
    worst = std::max(worst, (back - uv).norm());
  }
  RecordProperty("worst_round_trip_px", std::to_string(worst));
  // Measured 5e-7 px (PROJ's inverse Lambert iterates to ~1e-10 rad, GeographicLib's
  // LocalCartesian is exact to ~1e-9 m). Bound: 1e-5 px, well below the required 1e-3.
  EXPECT_LT(worst, 1e-5);
  // Outside the image the mapping still works (it is the CRS's, not the image's).
  EXPECT_FALSE(ortho.Covers(ortho.PixelToEnu(-3.0, 10.0)));
  EXPECT_TRUE(ortho.Covers(ortho.PixelToEnu(-0.4, 10.0)));
  EXPECT_NEAR(ortho.EnuToPixel(ortho.PixelToEnu(-300.0, 5000.0)).x(), -300.0, 1e-5);
}

TEST(AutzenOrthophoto, GroundSampleDistanceIsOneFootOverTheLambertScale) {
  SKERRY_SKIP_WITHOUT(kAutzenJpg);
  const LocalFrame frame = AutzenFrame();
  const Orthophoto ortho(kAutzenJpg, frame);
  // One international foot of grid is 0.3048 / k m on the ellipsoid (k < 1 between the standard
  // parallels 43 and 45.5 N).
  const double k = Lambert().k(frame.origin().lat_deg * kDeg);
  const double expected = 0.3048 / k;
  RecordProperty("gsd_m", std::to_string(ortho.ground_sample_distance_m()));
  EXPECT_LT(k, 1.0);
  EXPECT_NEAR(ortho.gsd_m().x(), expected, 1e-6);
  EXPECT_NEAR(ortho.gsd_m().y(), expected, 1e-6);
  EXPECT_NEAR(ortho.ground_sample_distance_m(), 0.3048, 1e-4);  // "about 1 ft"
  // If the feet were read as metres the image would be 3.3 km wide, not 1 km.
  EXPECT_NEAR(ortho.footprint_box_enu().sizes().y(), 4385 * 0.3048, 60.0);
}

TEST(AutzenOrthophoto, TheLambertGridIsRotatedByTheMeridianConvergence) {
  SKERRY_SKIP_WITHOUT(kAutzenJpg);
  const LocalFrame frame = AutzenFrame();
  const Orthophoto ortho(kAutzenJpg, frame);
  // Image "up" at the centre, in ENU: the grid north, which leans from true north by
  // gamma = n (lon - lon0), lon0 = -120.5 (2.6 degrees east of Eugene): 1.79 degrees.
  const Eigen::Vector3d up =
      ortho.PixelToEnu(1623.5, 2192.0 - 100.0) - ortho.PixelToEnu(1623.5, 2192.0 + 100.0);
  const double gamma = std::atan2(up.x(), up.y()) / kDeg;
  const double expected = Lambert().n() * (frame.origin().lon_deg - (-120.5));
  RecordProperty("convergence_deg", std::to_string(gamma));
  EXPECT_NEAR(gamma, expected, 1e-3);
  EXPECT_NEAR(std::abs(gamma), 1.79, 0.01);
  // So the footprint is a rotated rectangle: 64 points, counter-clockwise.
  const std::vector<Eigen::Vector2d>& fp = ortho.footprint_enu();
  ASSERT_EQ(fp.size(), 64u);
  double area2 = 0.0;
  for (size_t i = 0; i < fp.size(); ++i) {
    const Eigen::Vector2d& a = fp[i];
    const Eigen::Vector2d& b = fp[(i + 1) % fp.size()];
    area2 += a.x() * b.y() - b.x() * a.y();
  }
  EXPECT_GT(area2, 0.0);
  EXPECT_NEAR(0.5 * area2, 3248 * 4385 * std::pow(ortho.ground_sample_distance_m(), 2),
              1e-3 * 0.5 * area2);
}

TEST(AutzenOrthophoto, ImageIsBgrWithGdalsBands) {
  SKERRY_SKIP_WITHOUT(kAutzenJpg);
  const Orthophoto ortho(kAutzenJpg, LocalFrame({44.05, -123.07, 100.0}));
  ASSERT_EQ(ortho.image().type(), CV_8UC3);
  GDALAllRegister();
  std::unique_ptr<GDALDataset> ds(
      GDALDataset::FromHandle(GDALOpen(kAutzenJpg.c_str(), GA_ReadOnly)));
  ASSERT_TRUE(ds);
  // The whole R, G, B bands straight from GDAL (one JPEG decode).
  const int w = ds->GetRasterXSize();
  const int h = ds->GetRasterYSize();
  std::vector<std::uint8_t> rgb(3 * static_cast<size_t>(w) * h);
  ASSERT_EQ(ds->RasterIO(GF_Read, 0, 0, w, h, rgb.data(), w, h, GDT_Byte, 3, nullptr, 1, w,
                         static_cast<GSpacing>(w) * h, nullptr),
            CE_None);
  const auto band = [&](int b, int row, int col) {
    return rgb[static_cast<size_t>(b) * w * h + static_cast<size_t>(row) * w + col];
  };
  std::mt19937 rng(2);
  int differing_channels = 0;
  for (int k = 0; k < 2000; ++k) {
    const int col = static_cast<int>(rng() % w);
    const int row = static_cast<int>(rng() % h);
    const cv::Vec3b bgr = ortho.image().at<cv::Vec3b>(row, col);
    EXPECT_EQ(bgr[0], band(2, row, col));
    EXPECT_EQ(bgr[1], band(1, row, col));
    EXPECT_EQ(bgr[2], band(0, row, col));
    differing_channels += band(0, row, col) != band(2, row, col);
  }
  EXPECT_GT(differing_channels, 500);  // a colour image: the order matters
}

TEST(AutzenOrthophoto, CrsOverrideWorldFileAndPrjSidecarGiveTheSameMapping) {
  SKERRY_SKIP_WITHOUT(kAutzenJpg);
  const LocalFrame frame({44.0567, -123.0696, 100.0});
  const Orthophoto reference(kAutzenJpg, frame);
  const std::string dir = FreshDir("copies");
  // The JPEG with a .jgw world file and a .prj sidecar.
  testing::CopyTo(kAutzenJpg, dir, "photo.jpg");
  testing::CopyTo(kAutzenDir + "/autzen.wld", dir, "photo.jgw");
  testing::CopyTo(kAutzenDir + "/autzen-srs.wkt", dir, "photo.prj");
  const Orthophoto jgw(dir + "/photo.jpg", frame);
  EXPECT_EQ(jgw.crs_source(), "sidecar " + dir + "/photo.prj");
  // The original with the CRS given as the WKT file's path.
  OrthophotoOptions options;
  options.crs = kAutzenDir + "/autzen-srs.wkt";
  const Orthophoto overridden(kAutzenJpg, frame, options);
  EXPECT_EQ(overridden.crs_source(), "override");
  for (const Eigen::Vector2d& uv :
       {Eigen::Vector2d(0, 0), Eigen::Vector2d(3247, 4384), Eigen::Vector2d(1000.25, 17.5)}) {
    const Eigen::Vector3d p = reference.PixelToEnu(uv.x(), uv.y());
    EXPECT_LT((jgw.PixelToEnu(uv.x(), uv.y()) - p).norm(), 1e-6);
    EXPECT_LT((overridden.PixelToEnu(uv.x(), uv.y()) - p).norm(), 1e-6);
  }
  // The world file names the centre of the top-left pixel: 635615.9278659122 ft E,
  // 853362.1430851521 ft N. Placed on WGS84 by OGR here, it must be pixel (0, 0) exactly (a
  // corner convention would put it half a pixel, 0.22 m, away).
  OGRSpatialReference lambert;
  ASSERT_EQ(lambert.SetFromUserInput(options.crs.c_str()), OGRERR_NONE);
  OGRSpatialReference wgs84;
  wgs84.importFromEPSG(4326);
  lambert.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  std::unique_ptr<OGRCoordinateTransformation> t(
      OGRCreateCoordinateTransformation(&lambert, &wgs84));
  double x = 635615.9278659122;
  double y = 853362.1430851521;
  ASSERT_TRUE(t->Transform(1, &x, &y));
  EXPECT_LT((frame.ToEnu(y, x, 0.0) - reference.PixelToEnu(0.0, 0.0, 0.0)).norm(), 1e-3);
}

TEST(AutzenOrthophoto, GeoTiffWithEmbeddedCrsAndAWindowOffset) {
  SKERRY_SKIP_WITHOUT(kAutzenJpg);
  const LocalFrame frame({44.0567, -123.0696, 100.0});
  const Orthophoto reference(kAutzenJpg, frame);
  const std::string tif = FreshDir("tif") + "/window.tif";
  ASSERT_TRUE(testing::GdalTranslate(kAutzenJpg, tif,
                                     {"-of", "GTiff", "-srcwin", "1000", "2000", "300", "200",
                                      "-a_srs", kAutzenDir + "/autzen-srs.wkt"}));
  const Orthophoto window(tif, frame);
  EXPECT_EQ(window.crs_source(), "file");
  EXPECT_EQ(window.width(), 300);
  EXPECT_EQ(window.height(), 200);
  for (const Eigen::Vector2d& uv :
       {Eigen::Vector2d(0, 0), Eigen::Vector2d(299, 199), Eigen::Vector2d(12.5, 150.75)}) {
    const Eigen::Vector3d p = reference.PixelToEnu(uv.x() + 1000, uv.y() + 2000);
    EXPECT_LT((window.PixelToEnu(uv.x(), uv.y()) - p).norm(), 1e-6);
    EXPECT_EQ(window.image().at<cv::Vec3b>(static_cast<int>(uv.y()), static_cast<int>(uv.x())),
              reference.image().at<cv::Vec3b>(static_cast<int>(uv.y()) + 2000,
                                              static_cast<int>(uv.x()) + 1000));
  }
}

TEST(AutzenOrthophoto, NoCrsOrNoGeoreferencingIsAnInputError) {
  SKERRY_SKIP_WITHOUT(kAutzenJpg);
  const LocalFrame frame({44.0567, -123.0696, 100.0});
  const std::string dir = FreshDir("bare");
  const std::string no_crs = testing::CopyTo(kAutzenJpg, dir, "no_crs.jpg");
  testing::CopyTo(kAutzenDir + "/autzen.wld", dir, "no_crs.wld");
  ExpectInputError(
      [&] { Orthophoto(no_crs, frame); }, no_crs, "crs",
      {"no CRS", "no_crs.prj, no_crs.wkt or no_crs-srs.wkt", "OrthophotoOptions::crs"});
  OrthophotoOptions from_flag;
  from_flag.crs_given_as = "--image-crs";
  ExpectInputError([&] { Orthophoto(no_crs, frame, from_flag); }, no_crs, "crs",
                   {"as --image-crs"});
  const std::string no_geo = testing::CopyTo(kAutzenJpg, dir, "no_geo.jpg");
  testing::CopyTo(kAutzenDir + "/autzen-srs.wkt", dir, "no_geo.prj");
  ExpectInputError([&] { Orthophoto(no_geo, frame); }, no_geo, "geotransform",
                   {"no georeferencing"});
  OrthophotoOptions bad;
  bad.crs = "not a crs";
  ExpectInputError([&] { Orthophoto(kAutzenJpg, frame, bad); }, kAutzenJpg, "crs", {"not a crs"});
}

// The declared size is checked against OrthophotoOptions::max_pixels before any pixel is
// allocated: a GeoTIFF of a few hundred bytes declaring 10^10 RGB pixels would ask for 28 GiB.
TEST(SyntheticOrthophoto, AnImageDeclaringMorePixelsThanTheLimitIsRefusedBeforeItIsRead) {
  const std::string dir = FreshDir("size");
  const LocalFrame frame({47.45, 9.55, 0.0});
  const std::string huge =
      testing::MakeSparseGeoTiff(dir + "/huge.tif", 100000, 100000, 3, GDT_Byte);
  ASSERT_LT(fs::file_size(huge), 1u << 20);
  ExpectInputError([&] { Orthophoto(huge, frame); }, huge, "size",
                   {"100000 x 100000 = 10000000000 cells", "27.9 GiB",
                    "OrthophotoOptions::max_pixels", "gdal_translate -projwin"});

  // A grey image takes a byte a pixel in memory, a third of a colour one.
  const std::string grey =
      testing::MakeSparseGeoTiff(dir + "/grey.tif", 100000, 100000, 1, GDT_Byte);
  ExpectInputError([&] { Orthophoto(grey, frame); }, grey, "size", {"(9.3 GiB in memory)"});

  const std::string small = testing::MakeSparseGeoTiff(dir + "/small.tif", 100, 50, 1, GDT_Byte);
  OrthophotoOptions tight;
  tight.max_pixels = 4999;
  ExpectInputError([&] { Orthophoto(small, frame, tight); }, small, "size",
                   {"100 x 50 = 5000 cells"});
  tight.max_pixels = 5000;
  const Orthophoto fits(small, frame, tight);
  EXPECT_EQ(fits.width(), 100);
  EXPECT_EQ(fits.height(), 50);
  tight.max_pixels = -1;
  EXPECT_THROW(Orthophoto(small, frame, tight), std::invalid_argument);
}

// A north-up GeoTIFF on EPSG:4326 near Lake Constance: `bands` bands of `type`, cell (row, col)
// of band b (0-based) = value(b, row, col); `nodata` declared on every band when given.
std::string WriteGeoTiff(const std::string& path,
                         int cols,
                         int rows,
                         int bands,
                         GDALDataType type,
                         const std::function<double(int, int, int)>& value,
                         std::optional<double> nodata = std::nullopt) {
  GDALAllRegister();
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  std::unique_ptr<GDALDataset> ds(driver->Create(path.c_str(), cols, rows, bands, type, nullptr));
  EXPECT_TRUE(ds) << path;
  if (!ds) return path;
  double gt[6] = {9.5, 1e-5, 0.0, 47.5, 0.0, -1e-5};
  ds->SetGeoTransform(gt);
  OGRSpatialReference wgs84;
  wgs84.importFromEPSG(4326);
  ds->SetSpatialRef(&wgs84);
  std::vector<double> cells(static_cast<size_t>(cols) * rows);
  for (int b = 0; b < bands; ++b) {
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < cols; ++c) cells[static_cast<size_t>(r) * cols + c] = value(b, r, c);
    }
    GDALRasterBand* band = ds->GetRasterBand(b + 1);
    if (nodata) band->SetNoDataValue(*nodata);
    EXPECT_EQ(band->RasterIO(GF_Write, 0, 0, cols, rows, cells.data(), cols, rows, GDT_Float64, 0,
                             0, nullptr),
              CE_None);
  }
  return path;
}

// A 16-bit scene that uses 2550 of its 65536 levels (a 12-bit sensor's kind), with 20 hot pixels
// at 65535: stretched between its 0.5 % and 99.5 % quantiles it fills the 256 grey levels, where
// a stretch from its minimum to its maximum would squeeze it into ten.
TEST(SyntheticOrthophoto, SixteenBitCellsAreStretchedBetweenTheirQuantiles) {
  const std::string dir = FreshDir("deep");
  const LocalFrame frame({47.4997, 9.5013, 0.0});
  const auto scene = [](int, int row, int col) {
    return row == 7 && col < 20 ? 65535.0 : 1000.0 + 10.0 * col;
  };
  const std::string tif = WriteGeoTiff(dir + "/u16.tif", 256, 64, 1, GDT_UInt16, scene);
  const Orthophoto ortho(tif, frame);
  ASSERT_EQ(ortho.image().type(), CV_8UC1);
  // 16384 cells: 63 per value in the first 20 columns, 64 in the others, and 20 hot ones. The
  // 0.5 % quantile (the 82nd cell) lies in column 1 (1010); the 99.5 % one has 82 cells above it,
  // the 20 hot ones and 62 of column 255's (3550).
  EXPECT_GT(ortho.value_range().x(), 1010.0);
  EXPECT_LT(ortho.value_range().x(), 1011.0);
  EXPECT_GT(ortho.value_range().y(), 3549.0);
  EXPECT_LT(ortho.value_range().y(), 3550.0);
  for (int col = 0; col < 256; ++col) {
    const double expected = std::clamp(255.0 * (scene(0, 0, col) - ortho.value_range().x()) /
                                           (ortho.value_range().y() - ortho.value_range().x()),
                                       0.0, 255.0);
    EXPECT_NEAR(ortho.image().at<std::uint8_t>(0, col), expected, 0.51) << col;
    EXPECT_NEAR(ortho.image().at<std::uint8_t>(63, col), 255.0 * col / 255.0, 2.6) << col;
  }
  for (int col = 0; col < 20; ++col) EXPECT_EQ(ortho.image().at<std::uint8_t>(7, col), 255);

  // No clipping: the minimum and the maximum, and the scene in 10 grey levels.
  OrthophotoOptions full;
  full.clip_fraction = 0.0;
  const Orthophoto squeezed(tif, frame, full);
  EXPECT_DOUBLE_EQ(squeezed.value_range().x(), 1000.0);
  EXPECT_DOUBLE_EQ(squeezed.value_range().y(), 65535.0);
  EXPECT_LE(squeezed.image().at<std::uint8_t>(0, 255), 10);
  full.clip_fraction = 0.5;
  EXPECT_THROW(Orthophoto(tif, frame, full), std::invalid_argument);
}

// Float reflectances in three bands with a no-data block and a NaN block: both are left out of the
// stretch and become 0; one mapping for all bands keeps grey cells grey, and the bands land in
// BGR order as for 8-bit images.
TEST(SyntheticOrthophoto, FloatBandsKeepTheirColoursAndNoDataAndNanBecomeZero) {
  const std::string dir = FreshDir("float");
  const LocalFrame frame({47.4997, 9.5013, 0.0});
  constexpr double kNoData = 9999.0;  // above every value: unless left out, it would be 255
  const auto scene = [](int band, int row, int col) {
    if (row < 10 && col < 10) return kNoData;
    if (row >= 90 && col >= 90) return std::numeric_limits<double>::quiet_NaN();
    if (row == 50) return band == 0 ? 0.8 : 0.1;  // a red row (band 1 = red, 3 = blue)
    return 0.1 + 0.7 * col / 99.0;                // grey, dark to bright
  };
  const std::string tif = WriteGeoTiff(dir + "/f32.tif", 100, 100, 3, GDT_Float32, scene, kNoData);
  const Orthophoto ortho(tif, frame);
  ASSERT_EQ(ortho.image().type(), CV_8UC3);
  EXPECT_GT(ortho.value_range().x(), 0.09);
  EXPECT_LT(ortho.value_range().y(), 0.81);
  EXPECT_EQ(ortho.image().at<cv::Vec3b>(0, 0), cv::Vec3b(0, 0, 0));
  EXPECT_EQ(ortho.image().at<cv::Vec3b>(99, 99), cv::Vec3b(0, 0, 0));
  for (int col = 10; col < 100; col += 7) {
    const cv::Vec3b grey = ortho.image().at<cv::Vec3b>(30, col);
    EXPECT_EQ(grey[0], grey[1]);
    EXPECT_EQ(grey[1], grey[2]);
    EXPECT_NEAR(grey[0], 255.0 * (col - 1.0) / 97.0, 3.0) << col;
    const cv::Vec3b red = ortho.image().at<cv::Vec3b>(50, col);
    EXPECT_LE(red[0], 3);
    EXPECT_LE(red[1], 3);
    EXPECT_GE(red[2], 250);
  }
  // The no-data and NaN blocks hold no data; a row with data in its red band only does.
  ASSERT_FALSE(ortho.valid_mask().empty());
  EXPECT_EQ(cv::countNonZero(ortho.valid_mask() == 0), 200);
  EXPECT_EQ(ortho.valid_mask().at<std::uint8_t>(0, 0), 0);
  EXPECT_EQ(ortho.valid_mask().at<std::uint8_t>(99, 99), 0);
  EXPECT_EQ(ortho.valid_mask().at<std::uint8_t>(50, 50), 255);
  EXPECT_DOUBLE_EQ(ortho.valid_share(), 0.98);
}

// 8-bit cells at their band's no-data value in every band hold no data: valid_mask() marks them,
// they are 0 in the image, and HoldsData() is false over them where Covers() stays true. A pixel
// at no-data in one band only holds data. Without a declared no-data value every pixel does.
TEST(SyntheticOrthophoto, EightBitNoDataCellsHoldNoData) {
  const std::string dir = FreshDir("nodata8");
  const LocalFrame frame({47.4997, 9.5013, 0.0});
  constexpr double kNoData = 200.0;  // inside the scene's range: only the mask tells it apart
  const auto scene = [](int band, int row, int col) {
    if (row < 20 && col < 30) return kNoData;                       // a masked corner
    if (row == 50 && col == 50) return band == 0 ? kNoData : 10.0;  // red at no-data only
    return 40.0 + 30.0 * band + (row + col) % 7;
  };
  const std::string tif = WriteGeoTiff(dir + "/rgb.tif", 100, 80, 3, GDT_Byte, scene, kNoData);
  const Orthophoto ortho(tif, frame);
  ASSERT_EQ(ortho.image().type(), CV_8UC3);
  ASSERT_FALSE(ortho.valid_mask().empty());
  EXPECT_EQ(cv::countNonZero(ortho.valid_mask() == 0), 20 * 30);
  EXPECT_DOUBLE_EQ(ortho.valid_share(), 1.0 - 600.0 / 8000.0);
  EXPECT_EQ(ortho.image().at<cv::Vec3b>(5, 5), cv::Vec3b(0, 0, 0));
  EXPECT_EQ(ortho.image().at<cv::Vec3b>(50, 50), cv::Vec3b(10, 10, 200));
  const Eigen::Vector3d masked = ortho.PixelToEnu(5, 5);
  const Eigen::Vector3d photo = ortho.PixelToEnu(60, 60);
  EXPECT_TRUE(ortho.Covers(masked));
  EXPECT_FALSE(ortho.HoldsData(masked));
  EXPECT_TRUE(ortho.HoldsData(photo));
  EXPECT_FALSE(ortho.HoldsData(ortho.PixelToEnu(-3, 60)));

  const Orthophoto plain(WriteGeoTiff(dir + "/plain.tif", 100, 80, 3, GDT_Byte, scene), frame);
  EXPECT_TRUE(plain.valid_mask().empty());
  EXPECT_EQ(plain.valid_share(), 1.0);
  EXPECT_EQ(plain.image().at<cv::Vec3b>(5, 5), cv::Vec3b(200, 200, 200));
  EXPECT_TRUE(plain.HoldsData(masked));
}

// A transparent alpha band (GDAL's mask, RFC 15) marks pixels without data as a no-data value
// does; half-transparent ones (alpha < 128) count as transparent.
TEST(SyntheticOrthophoto, TransparentAlphaCellsHoldNoData) {
  const std::string dir = FreshDir("alpha");
  const LocalFrame frame({47.4997, 9.5013, 0.0});
  const auto scene = [](int band, int row, int col) {
    if (band == 3) return row < 10 ? 0.0 : (row < 12 ? 127.0 : (row < 14 ? 128.0 : 255.0));
    return 50.0 + 20.0 * band + col % 5;
  };
  const std::string tif = WriteGeoTiff(dir + "/rgba.tif", 60, 40, 4, GDT_Byte, scene);
  {
    std::unique_ptr<GDALDataset> ds(GDALDataset::FromHandle(GDALOpen(tif.c_str(), GA_Update)));
    ASSERT_TRUE(ds);
    ASSERT_EQ(ds->GetRasterBand(4)->SetColorInterpretation(GCI_AlphaBand), CE_None);
  }
  const Orthophoto ortho(tif, frame);
  ASSERT_EQ(ortho.image().type(), CV_8UC3);
  ASSERT_FALSE(ortho.valid_mask().empty());
  EXPECT_EQ(cv::countNonZero(ortho.valid_mask()(cv::Rect(0, 0, 60, 12)) != 0), 0);
  EXPECT_EQ(cv::countNonZero(ortho.valid_mask()(cv::Rect(0, 12, 60, 28)) == 0), 0);
  EXPECT_EQ(ortho.image().at<cv::Vec3b>(0, 0), cv::Vec3b(0, 0, 0));
  EXPECT_EQ(ortho.image().at<cv::Vec3b>(20, 0), cv::Vec3b(90, 70, 50));
}

// A 16-bit mosaic whose border is transparent (an alpha band, the border's colour 0): the stretch
// is the photo's, not pulled down to the border's 0 by its 40 % of the cells, and the border holds
// no data.
TEST(SyntheticOrthophoto, TransparentCellsStayOutOfADeeperImagesStretch) {
  const std::string dir = FreshDir("alpha16");
  const LocalFrame frame({47.4997, 9.5013, 0.0});
  const auto scene = [](int band, int row, int col) {
    if (band == 3) return row < 16 ? 0.0 : 65535.0;
    return row < 16 ? 0.0 : 1000.0 + 10.0 * col;  // 1000..1590
  };
  const std::string tif = WriteGeoTiff(dir + "/rgba16.tif", 60, 40, 4, GDT_UInt16, scene);
  {
    std::unique_ptr<GDALDataset> ds(GDALDataset::FromHandle(GDALOpen(tif.c_str(), GA_Update)));
    ASSERT_TRUE(ds);
    ASSERT_EQ(ds->GetRasterBand(4)->SetColorInterpretation(GCI_AlphaBand), CE_None);
  }
  OrthophotoOptions full;
  full.clip_fraction = 0.0;
  const Orthophoto ortho(tif, frame, full);
  ASSERT_EQ(ortho.image().type(), CV_8UC3);
  EXPECT_DOUBLE_EQ(ortho.value_range().x(), 1000.0);
  EXPECT_DOUBLE_EQ(ortho.value_range().y(), 1590.0);
  ASSERT_FALSE(ortho.valid_mask().empty());
  EXPECT_EQ(cv::countNonZero(ortho.valid_mask() == 0), 16 * 60);
  EXPECT_EQ(ortho.image().at<cv::Vec3b>(20, 0), cv::Vec3b(0, 0, 0));
  EXPECT_EQ(ortho.image().at<cv::Vec3b>(20, 59), cv::Vec3b(255, 255, 255));
  // With the default clip, the quantiles of the photo's cells: within its range.
  const Orthophoto clipped(tif, frame);
  EXPECT_GT(clipped.value_range().x(), 1000.0);
  EXPECT_LT(clipped.value_range().y(), 1590.0);
  // Every cell masked: no cell to stretch, an error naming the file.
  const std::string none =
      WriteGeoTiff(dir + "/none16.tif", 20, 10, 4, GDT_UInt16,
                   [](int band, int, int col) { return band == 3 ? 0.0 : 1000.0 + col; });
  {
    std::unique_ptr<GDALDataset> ds(GDALDataset::FromHandle(GDALOpen(none.c_str(), GA_Update)));
    ASSERT_TRUE(ds);
    ASSERT_EQ(ds->GetRasterBand(4)->SetColorInterpretation(GCI_AlphaBand), CE_None);
  }
  ExpectInputError([&] { Orthophoto(none, frame); }, none, "bands", {"no valid cell"});
}

// Infinite float cells are cells without data, as NaN ones: the stretch is taken over the finite
// cells and the image is read, where it used to be refused.
TEST(SyntheticOrthophoto, InfiniteCellsHoldNoDataAndStayOutOfTheStretch) {
  const std::string dir = FreshDir("inf");
  const LocalFrame frame({47.4997, 9.5013, 0.0});
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const auto scene = [&](int, int row, int col) {
    if (row == 3 && col < 10) return kInf;
    if (row == 4 && col < 10) return -kInf;
    return 100.0 + col;  // 100..149
  };
  OrthophotoOptions full;
  full.clip_fraction = 0.0;
  const std::string tif = WriteGeoTiff(dir + "/inf.tif", 50, 30, 1, GDT_Float32, scene);
  const Orthophoto ortho(tif, frame, full);
  ASSERT_EQ(ortho.image().type(), CV_8UC1);
  EXPECT_DOUBLE_EQ(ortho.value_range().x(), 100.0);
  EXPECT_DOUBLE_EQ(ortho.value_range().y(), 149.0);
  ASSERT_FALSE(ortho.valid_mask().empty());
  EXPECT_EQ(cv::countNonZero(ortho.valid_mask() == 0), 20);
  EXPECT_EQ(ortho.image().at<std::uint8_t>(3, 0), 0);
  EXPECT_EQ(ortho.image().at<std::uint8_t>(4, 5), 0);
  EXPECT_EQ(ortho.image().at<std::uint8_t>(3, 49), 255);
  EXPECT_EQ(ortho.image().at<std::uint8_t>(5, 0), 0);
  // Infinite everywhere: nothing to stretch.
  const std::string all_inf =
      WriteGeoTiff(dir + "/all_inf.tif", 8, 8, 1, GDT_Float32, [&](int, int, int) { return kInf; });
  ExpectInputError([&] { Orthophoto(all_inf, frame); }, all_inf, "bands", {"no valid cell"});
}

TEST(SyntheticOrthophoto, ComplexCellsAndBandsWithoutValidCellsAreInputErrors) {
  const std::string dir = FreshDir("bad");
  const LocalFrame frame({47.4997, 9.5013, 0.0});
  const auto one = [](int, int, int) { return 1.0; };
  const std::string complex = WriteGeoTiff(dir + "/complex.tif", 8, 8, 1, GDT_CInt16, one);
  ExpectInputError([&] { Orthophoto(complex, frame); }, complex, "bands",
                   {"band 1", "complex", "CInt16"});
  const std::string empty =
      WriteGeoTiff(dir + "/empty.tif", 8, 8, 3, GDT_UInt16, one, /*nodata=*/1.0);
  ExpectInputError([&] { Orthophoto(empty, frame); }, empty, "bands", {"no valid cell"});
  // A palette on 16-bit indices (GeoTIFF allows it; its colours are not read).
  const std::string palette = WriteGeoTiff(dir + "/palette.tif", 8, 8, 1, GDT_UInt16, one);
  {
    std::unique_ptr<GDALDataset> ds(GDALDataset::FromHandle(GDALOpen(palette.c_str(), GA_Update)));
    ASSERT_TRUE(ds);
    GDALColorTable table;
    const GDALColorEntry red = {255, 0, 0, 255};
    table.SetColorEntry(1, &red);
    ds->GetRasterBand(1)->SetColorInterpretation(GCI_PaletteIndex);
    ASSERT_EQ(ds->GetRasterBand(1)->SetColorTable(&table), CE_None);
  }
  ExpectInputError([&] { Orthophoto(palette, frame); }, palette, "bands", {"palette", "UInt16"});
}

// The real photo as a 16-bit GeoTIFF (each 8-bit value v written as 257 v, as a 16-bit export of
// an 8-bit image does): stretched from its minimum to its maximum it is the 8-bit image again,
// to the rounding of the stretch.
TEST(AutzenOrthophoto, ASixteenBitCopyIsTheSameImage) {
  SKERRY_SKIP_WITHOUT(kAutzenJpg);
  const LocalFrame frame({44.0567, -123.0696, 100.0});
  const Orthophoto reference(kAutzenJpg, frame);
  const std::string tif = FreshDir("u16") + "/window16.tif";
  ASSERT_TRUE(testing::GdalTranslate(
      kAutzenJpg, tif,
      {"-of", "GTiff", "-ot", "UInt16", "-scale", "0", "255", "0", "65535", "-srcwin", "1000",
       "2000", "600", "400", "-a_srs", kAutzenDir + "/autzen-srs.wkt"}));

  const cv::Mat window8 = reference.image()(cv::Rect(1000, 2000, 600, 400));
  double lo8 = 0.0;
  double hi8 = 0.0;
  cv::minMaxLoc(window8.reshape(1), &lo8, &hi8);
  ASSERT_LT(lo8, hi8);
  OrthophotoOptions full;
  full.clip_fraction = 0.0;
  const Orthophoto deep(tif, frame, full);
  ASSERT_EQ(deep.image().type(), CV_8UC3);
  EXPECT_DOUBLE_EQ(deep.value_range().x(), 257.0 * lo8);
  EXPECT_DOUBLE_EQ(deep.value_range().y(), 257.0 * hi8);
  cv::Mat expected;
  window8.convertTo(expected, CV_8UC3, 255.0 / (hi8 - lo8), -255.0 * lo8 / (hi8 - lo8));
  cv::Mat diff;
  cv::absdiff(deep.image(), expected, diff);
  double worst = 0.0;
  cv::minMaxLoc(diff.reshape(1), nullptr, &worst);
  EXPECT_LE(worst, 1.0);
  for (const Eigen::Vector2d& uv : {Eigen::Vector2d(0, 0), Eigen::Vector2d(599, 399)}) {
    EXPECT_LT((deep.PixelToEnu(uv.x(), uv.y()) - reference.PixelToEnu(uv.x() + 1000, uv.y() + 2000))
                  .norm(),
              1e-6);
  }
}

// Gives the 8-bit band 1 of `tif` a palette: red, green and a dark blue-grey.
void SetThreeColourPalette(const std::string& tif) {
  std::unique_ptr<GDALDataset> ds(GDALDataset::FromHandle(GDALOpen(tif.c_str(), GA_Update)));
  ASSERT_TRUE(ds) << tif;
  GDALColorTable table;
  const GDALColorEntry colours[3] = {{255, 0, 0, 255}, {0, 255, 0, 255}, {10, 20, 30, 255}};
  for (int i = 0; i < 3; ++i) table.SetColorEntry(i, &colours[i]);
  ds->GetRasterBand(1)->SetColorInterpretation(GCI_PaletteIndex);
  ASSERT_EQ(ds->GetRasterBand(1)->SetColorTable(&table), CE_None);
}

// Where a window of pixels holds data: its mask, or 255 everywhere when the mask is empty.
cv::Mat ValidOf(const OrthophotoPixels& p) {
  return p.valid.empty() ? cv::Mat(p.rect.size(), CV_8UC1, cv::Scalar(255)) : p.valid;
}

// With its pixels left on disk, an orthophoto reads the windows asked for from the file: each is
// the in-memory image's and mask there to the byte, for every kind of image the reader takes
// (8-bit colour, a palette, 8-bit grey with a no-data value, 16-bit colour with a transparent
// border, float with no-data, NaN and infinite cells), across the image's edges too; the stretch
// is the whole image's, not the window's.
TEST(SyntheticOrthophoto, WindowsReadFromDiskAreTheImageInMemory) {
  const std::string dir = FreshDir("on_disk");
  const LocalFrame frame({47.4997, 9.5013, 0.0});
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const auto set_alpha = [](const std::string& tif) {
    std::unique_ptr<GDALDataset> ds(GDALDataset::FromHandle(GDALOpen(tif.c_str(), GA_Update)));
    EXPECT_TRUE(ds);
    if (ds) ds->GetRasterBand(4)->SetColorInterpretation(GCI_AlphaBand);
  };
  std::vector<std::string> images = {
      WriteGeoTiff(dir + "/rgb.tif", 60, 40, 3, GDT_Byte,
                   [](int b, int r, int c) { return (b * 50 + r * 3 + c * 7) % 256; }),
      WriteGeoTiff(
          dir + "/grey_nodata.tif", 60, 40, 1, GDT_Byte,
          [](int, int r, int c) { return c < 9 ? 0.0 : (r * 5 + c) % 256; }, 0.0),
      WriteGeoTiff(dir + "/rgba16.tif", 60, 40, 4, GDT_UInt16,
                   [](int b, int r, int c) {
                     if (b == 3) return r < 16 ? 0.0 : 65535.0;
                     return r < 16 ? 0.0 : 1000.0 + 10.0 * c + 37.0 * ((r * c) % 7);
                   }),
      WriteGeoTiff(
          dir + "/float.tif", 60, 40, 1, GDT_Float32,
          [&](int, int r, int c) {
            if (r == 3 && c < 10) return kInf;
            if (r == 5) return std::numeric_limits<double>::quiet_NaN();
            if (c > 50) return -9999.0;
            return 100.0 + c * r;
          },
          -9999.0),
      WriteGeoTiff(dir + "/palette.tif", 60, 40, 1, GDT_Byte,
                   [](int, int r, int c) { return (r + c) % 3; })};
  set_alpha(images[2]);
  SetThreeColourPalette(images[4]);
  OrthophotoOptions disk_options;
  disk_options.on_disk = true;
  for (const std::string& tif : images) {
    SCOPED_TRACE(tif);
    const Orthophoto memory(tif, frame);
    const Orthophoto disk(tif, frame, disk_options);
    EXPECT_FALSE(memory.on_disk());
    EXPECT_TRUE(disk.on_disk());
    EXPECT_TRUE(disk.image().empty());
    EXPECT_TRUE(std::isnan(disk.valid_share()));
    EXPECT_EQ(disk.width(), memory.width());
    EXPECT_EQ(disk.height(), memory.height());
    EXPECT_EQ(disk.value_range(), memory.value_range());
    int compared = 0;
    for (const cv::Rect& window :
         {cv::Rect(0, 0, 60, 40), cv::Rect(5, 7, 20, 11), cv::Rect(-5, -3, 15, 10),
          cv::Rect(50, 30, 30, 30), cv::Rect(0, 14, 60, 4), cv::Rect(100, 100, 5, 5)}) {
      const OrthophotoPixels a = memory.Pixels(window);
      const OrthophotoPixels b = disk.Pixels(window);
      EXPECT_EQ(a.rect, b.rect) << window;
      EXPECT_EQ(a.rect, window & cv::Rect(0, 0, 60, 40));
      if (a.rect.empty()) continue;
      ++compared;
      ASSERT_EQ(a.image.type(), b.image.type());
      ASSERT_EQ(a.image.size(), b.image.size());
      EXPECT_EQ(cv::norm(a.image, b.image, cv::NORM_INF), 0.0) << window;
      EXPECT_EQ(cv::norm(ValidOf(a), ValidOf(b), cv::NORM_INF), 0.0) << window;
    }
    EXPECT_EQ(compared, 5);
    for (const Eigen::Vector2d& uv :
         {Eigen::Vector2d(0, 0), Eigen::Vector2d(4, 3), Eigen::Vector2d(30, 5),
          Eigen::Vector2d(55, 20), Eigen::Vector2d(30, 30)}) {
      const Eigen::Vector3d p = memory.PixelToEnu(uv.x(), uv.y());
      EXPECT_EQ(disk.HoldsData(p), memory.HoldsData(p)) << uv.transpose();
    }
  }
}

// An image larger than max_pixels cannot be held in memory, but with its pixels on disk it opens
// (even one declaring 10^10 pixels) and reads windows up to the limit; a larger window is an
// InputError naming the file.
TEST(SyntheticOrthophoto, OnDiskTheLimitBoundsEachWindowNotTheImage) {
  const std::string dir = FreshDir("on_disk_size");
  const LocalFrame frame({47.45, 9.55, 0.0});
  OrthophotoOptions o;
  o.on_disk = true;
  const std::string huge =
      testing::MakeSparseGeoTiff(dir + "/huge.tif", 100000, 100000, 3, GDT_Byte);
  const Orthophoto big(huge, frame, o);
  EXPECT_EQ(big.width(), 100000);
  const OrthophotoPixels corner = big.Pixels(cv::Rect(99900, 99950, 256, 256));
  EXPECT_EQ(corner.rect, cv::Rect(99900, 99950, 100, 50));
  EXPECT_EQ(corner.image.type(), CV_8UC3);
  EXPECT_EQ(corner.image.size(), cv::Size(100, 50));

  const std::string small = testing::MakeSparseGeoTiff(dir + "/small.tif", 100, 50, 1, GDT_Byte);
  o.max_pixels = 1000;
  OrthophotoOptions in_memory = o;
  in_memory.on_disk = false;
  ExpectInputError([&] { Orthophoto(small, frame, in_memory); }, small, "size",
                   {"100 x 50 = 5000 cells"});
  const Orthophoto windows(small, frame, o);
  EXPECT_EQ(windows.Pixels(cv::Rect(10, 10, 40, 25)).image.size(), cv::Size(40, 25));
  ExpectInputError([&] { windows.Pixels(cv::Rect(10, 10, 40, 26)); }, small, "size",
                   {"40 x 26 pixels", "OrthophotoOptions::max_pixels (1000)"});
}

// Read reduced, a window is the block means of the image's pixels, checked block by block
// against cv::mean over the block's pixels that hold data, rounded (a block holds data when at
// least half of its pixels do); the same to the byte with the pixels on disk (read in strips) and
// in memory, for colour, grey with a no-data value, float with NaN and no-data, and a palette,
// with factors that cut the window's last blocks short.
TEST(SyntheticOrthophoto, AReducedWindowIsTheMeanOfEachBlocksPixelsThatHoldData) {
  const std::string dir = FreshDir("reduced");
  const LocalFrame frame({47.4997, 9.5013, 0.0});
  std::vector<std::string> images = {
      WriteGeoTiff(dir + "/rgb.tif", 61, 43, 3, GDT_Byte,
                   [](int b, int r, int c) { return (b * 50 + r * 13 + c * 7 + r * c) % 256; }),
      WriteGeoTiff(
          dir + "/grey_nodata.tif", 61, 43, 1, GDT_Byte,
          [](int, int r, int c) { return (c + r) % 11 < 4 || c < 9 ? 0.0 : (r * 5 + c) % 256; },
          0.0),
      WriteGeoTiff(
          dir + "/float.tif", 61, 43, 1, GDT_Float32,
          [](int, int r, int c) {
            if (r == 5) return std::numeric_limits<double>::quiet_NaN();
            if (c > 50) return -9999.0;
            return 100.0 + c * r;
          },
          -9999.0),
      WriteGeoTiff(dir + "/palette.tif", 61, 43, 1, GDT_Byte,
                   [](int, int r, int c) { return (r + 2 * c) % 3; })};
  SetThreeColourPalette(images[3]);
  OrthophotoOptions disk_options;
  disk_options.on_disk = true;
  for (const std::string& tif : images) {
    SCOPED_TRACE(tif);
    const Orthophoto memory(tif, frame);
    const Orthophoto disk(tif, frame, disk_options);
    const cv::Mat whole_valid = memory.valid_mask().empty()
                                    ? cv::Mat(memory.image().size(), CV_8UC1, cv::Scalar(255))
                                    : memory.valid_mask();
    int blocks = 0, without_data = 0;
    for (const int factor : {2, 3, 7}) {
      for (const cv::Rect& window :
           {cv::Rect(0, 0, 61, 43), cv::Rect(5, 7, 20, 11), cv::Rect(-5, -3, 15, 10)}) {
        SCOPED_TRACE(::testing::Message() << "factor " << factor << " window " << window);
        const OrthophotoPixels a = memory.Pixels(window, factor);
        const OrthophotoPixels b = disk.Pixels(window, factor);
        EXPECT_EQ(a.factor, factor);
        EXPECT_EQ(a.rect, window & cv::Rect(0, 0, 61, 43));
        EXPECT_EQ(b.rect, a.rect);
        const cv::Size reduced((a.rect.width + factor - 1) / factor,
                               (a.rect.height + factor - 1) / factor);
        ASSERT_EQ(a.image.size(), reduced);
        ASSERT_EQ(b.image.size(), reduced);
        ASSERT_EQ(a.image.type(), memory.image().type());
        EXPECT_EQ(cv::norm(a.image, b.image, cv::NORM_INF), 0.0);
        const cv::Mat va = a.valid.empty() ? cv::Mat(reduced, CV_8UC1, cv::Scalar(255)) : a.valid;
        const cv::Mat vb = b.valid.empty() ? cv::Mat(reduced, CV_8UC1, cv::Scalar(255)) : b.valid;
        EXPECT_EQ(cv::norm(va, vb, cv::NORM_INF), 0.0);
        for (int j = 0; j < reduced.height; ++j) {
          for (int i = 0; i < reduced.width; ++i) {
            const cv::Rect block =
                cv::Rect(a.rect.x + i * factor, a.rect.y + j * factor, factor, factor) & a.rect;
            const cv::Mat holds = whole_valid(block);
            const int n = cv::countNonZero(holds);
            const bool expect_valid = n > 0 && 2 * n >= block.area();
            ++blocks;
            without_data += expect_valid ? 0 : 1;
            ASSERT_EQ(va.at<std::uint8_t>(j, i) != 0, expect_valid) << i << "," << j;
            const cv::Scalar mean =
                expect_valid ? cv::mean(memory.image()(block), holds) : cv::Scalar::all(0);
            for (int k = 0; k < a.image.channels(); ++k) {
              ASSERT_EQ(a.image.ptr<std::uint8_t>(j)[i * a.image.channels() + k],
                        std::lround(mean[k]))
                  << i << "," << j << " channel " << k;
            }
          }
        }
      }
    }
    EXPECT_GT(blocks, 500);
    if (!memory.valid_mask().empty()) EXPECT_GT(without_data, 10);
    EXPECT_EQ(memory.Pixels(cv::Rect(100, 100, 5, 5), 3).rect, cv::Rect());
    EXPECT_THROW(memory.Pixels(cv::Rect(0, 0, 5, 5), 0), std::invalid_argument);
  }
}

// With the pixels on disk, max_pixels bounds the reduced window, which is all that is held (the
// window is read in strips of whole blocks, here of 9 rows): a window too large at full
// resolution reads reduced, the same as in memory, and one too large even reduced is an
// InputError naming the file, the window and the factor.
TEST(SyntheticOrthophoto, OnDiskTheLimitBoundsTheReducedWindow) {
  const std::string dir = FreshDir("reduced_size");
  const LocalFrame frame({47.45, 9.55, 0.0});
  OrthophotoOptions o;
  o.on_disk = true;
  o.max_pixels = 1000;
  const std::string tif = WriteGeoTiff(
      dir + "/small.tif", 100, 50, 3, GDT_Byte,
      [](int b, int r, int c) { return r == 20 && c < 50 ? 0.0 : 1 + (b * 31 + r * 7 + c) % 255; },
      0.0);
  const Orthophoto windows(tif, frame, o);
  const Orthophoto memory(tif, frame);
  const cv::Rect window(0, 0, 100, 50);
  const OrthophotoPixels from_memory = memory.Pixels(window, 3);
  EXPECT_EQ(from_memory.image.size(), cv::Size(34, 17));
  EXPECT_EQ(cv::norm(windows.Pixels(window, 3).image, from_memory.image, cv::NORM_INF), 0.0);
  ExpectInputError([&] { windows.Pixels(window); }, tif, "size", {"100 x 50 pixels"});
  ExpectInputError(
      [&] { windows.Pixels(window, 2); }, tif, "size",
      {"100 x 50 pixels reduced 2 times is 50 x 25", "OrthophotoOptions::max_pixels (1000)"});
  const OrthophotoPixels reduced = windows.Pixels(window, 3);
  EXPECT_EQ(reduced.rect, window);
  EXPECT_EQ(reduced.image.size(), cv::Size(34, 17));
  EXPECT_EQ(reduced.image.type(), CV_8UC3);
}

}  // namespace
}  // namespace skerry::geo
