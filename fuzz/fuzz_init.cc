// Linked into every harness: quiet logging (a reader's warnings and OpenCV's
// decoder messages would cost more than the parse), nothing else.

#include <opencv2/core/utils/logger.hpp>

#include "util/logging.h"

extern "C" int LLVMFuzzerInitialize(int* /*argc*/, char*** /*argv*/) {
  mr::SetLogLevel(mr::LogLevel::kError);
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
  return 0;
}
