#include "skerry/geo/image_header.h"

#include "gdal_support.h"

namespace skerry::geo {

std::optional<ImageHeader> ReadImageHeader(const std::string& path) {
  internal::EnsureGdalRegistered();
  internal::QuietGdalErrors quiet;
  // The formats cameras write; not JPEG 2000, WebP and the rest GDAL would also try.
  const char* const drivers[] = {"PNG", "JPEG", "PNM", "BMP", "GTiff", nullptr};
  const char* const no_siblings[] = {nullptr};
  internal::GdalDatasetPtr dataset(GDALDataset::FromHandle(
      GDALOpenEx(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, drivers, nullptr, no_siblings)));
  if (!dataset || dataset->GetRasterXSize() < 1 || dataset->GetRasterYSize() < 1 ||
      dataset->GetRasterCount() < 1) {
    return std::nullopt;
  }
  ImageHeader header;
  header.width = dataset->GetRasterXSize();
  header.height = dataset->GetRasterYSize();
  header.bands = dataset->GetRasterCount();
  header.format = dataset->GetDriver() ? dataset->GetDriver()->GetDescription() : "";
  return header;
}

}  // namespace skerry::geo
