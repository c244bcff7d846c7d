// Timing of ComputeSimilarity on random 640x480 (or --cols/--rows) images.
// Usage: similarity_benchmark [cols rows repetitions]   (single-threaded OpenCV)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "refine/similarity.h"

namespace {
double ThreadCpuMs() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}
}  // namespace

int main(int argc, char** argv) {
  const int cols = argc > 1 ? std::atoi(argv[1]) : 640;
  const int rows = argc > 2 ? std::atoi(argv[2]) : 480;
  const int reps = argc > 3 ? std::max(1, std::atoi(argv[3])) : 30;
  cv::setNumThreads(1);
  cv::Mat I1(rows, cols, CV_32F), I2(rows, cols, CV_32F);
  cv::randu(I1, 0.0f, 1.0f);
  cv::randu(I2, 0.0f, 1.0f);
  cv::GaussianBlur(I1, I1, cv::Size(0, 0), 1.0);
  cv::GaussianBlur(I2, I2, cv::Size(0, 0), 1.0);
  cv::Mat mask(rows, cols, CV_8U, cv::Scalar(0));
  cv::ellipse(mask, cv::Point(cols / 2, rows / 2), cv::Size(cols * 2 / 5, rows * 2 / 5), 0, 0, 360,
              cv::Scalar(255), -1);
  // Two rounds over all configurations; only the second is printed (the first
  // lets the allocator settle: glibc returns large blocks to the kernel until
  // its mmap threshold has adapted, and the page faults are counted as CPU).
  for (int round = 0; round < 2; ++round)
  for (const char* method : {"zncc", "dcv"}) {
    for (const bool dbl : {false, true}) {
      for (const bool grad : {false, true}) {
        mr::SimilarityOptions o;
        o.method = method;
        o.double_precision = dbl;
        cv::Mat a = I1, b = I2;
        if (dbl) {
          I1.convertTo(a, CV_64F);
          I2.convertTo(b, CV_64F);
        }
        mr::ComputeSimilarity(a, b, mask, o, grad);  // warm-up
        // The minimum over repetitions is robust to other processes on the
        // machine; the median is printed too.
        // Wall time and this thread's CPU time (the latter is not inflated
        // by other processes time-slicing the core).
        std::vector<double> ms(reps), cpu(reps);
        double cost = 0;
        for (int i = 0; i < reps; ++i) {
          const auto t0 = std::chrono::steady_clock::now();
          const double c0 = ThreadCpuMs();
          cost = mr::ComputeSimilarity(a, b, mask, o, grad).cost;
          cpu[i] = ThreadCpuMs() - c0;
          ms[i] = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                      .count();
        }
        std::sort(ms.begin(), ms.end());
        std::sort(cpu.begin(), cpu.end());
        if (round == 0) continue;
        std::printf(
            "%dx%d %-4s %-6s %-13s wall min %6.2f median %6.2f | thread cpu min %6.2f median "
            "%6.2f ms (cost %.1f)\n",
            cols, rows, method, dbl ? "double" : "float", grad ? "cost+gradient" : "cost only",
            ms[0], ms[reps / 2], cpu[0], cpu[reps / 2], cost);
      }
    }
  }
  return 0;
}
