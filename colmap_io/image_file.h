#pragma once

// Reading the images and masks of a workspace exactly as COLMAP reads them.
//
// Raw pixels: EXIF orientation is ignored (COLMAP's image_undistorter copies
// the pixels and keeps the tag, so the poses belong to the stored pixels).
// Completeness: libjpeg only warns about a cut file ("Premature end of JPEG
// file") and OpenCV then returns an image whose missing rows are grey; so a
// JPEG must contain the end-of-image marker after its first scan and a PNG
// must contain its IEND chunk. Data after a complete image (zero padding,
// trailers some cameras append) is allowed.

#include <string>

#include <opencv2/core.hpp>

namespace mr {

// Throws InputError "<path>: truncated or corrupt image (...)" if `data`, the
// bytes of the file at `path`, is a JPEG or PNG that ends before its image
// does. Other formats are left to the decoder.
void CheckImageComplete(const std::string& path, const std::string& data);

// Reads an image file with cv::imread flags (cv::IMREAD_COLOR, _GRAYSCALE,
// _UNCHANGED; cv::IMREAD_IGNORE_ORIENTATION is added). `what` names the file
// in errors ("image", "mask"). Throws InputError naming the path if it is
// missing, is not a regular file, is truncated or cannot be decoded.
cv::Mat ReadImageFile(const std::string& path, int flags, const std::string& what = "image");

// ReadImageFile after the file was read: checks and decodes its bytes `data`
// (empty, too large, truncated, undecodable: InputError naming `path`).
cv::Mat DecodeImageFile(const std::string& path, const std::string& data, int flags,
                        const std::string& what = "image");

}  // namespace mr
