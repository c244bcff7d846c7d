// Timing of ComputeSimilarity on random 640x480 (or --cols/--rows) images.
// Usage: similarity_benchmark [cols rows repetitions]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <random>

#include <opencv2/imgproc.hpp>

#include "refine/similarity.h"

int main(int argc, char** argv) {
  const int cols = argc > 1 ? std::atoi(argv[1]) : 640;
  const int rows = argc > 2 ? std::atoi(argv[2]) : 480;
  const int reps = argc > 3 ? std::atoi(argv[3]) : 20;
  cv::Mat I1(rows, cols, CV_32F), I2(rows, cols, CV_32F);
  cv::randu(I1, 0.0f, 1.0f);
  cv::randu(I2, 0.0f, 1.0f);
  cv::GaussianBlur(I1, I1, cv::Size(0, 0), 1.0);
  cv::GaussianBlur(I2, I2, cv::Size(0, 0), 1.0);
  cv::Mat mask(rows, cols, CV_8U, cv::Scalar(0));
  cv::ellipse(mask, cv::Point(cols / 2, rows / 2), cv::Size(cols * 2 / 5, rows * 2 / 5), 0, 0, 360,
              cv::Scalar(255), -1);
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
        const auto t0 = std::chrono::steady_clock::now();
        double cost = 0;
        for (int i = 0; i < reps; ++i) cost += mr::ComputeSimilarity(a, b, mask, o, grad).cost;
        const double ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                .count() /
            reps;
        std::printf("%dx%d %-4s %-6s %-13s %7.2f ms/pair (cost %.1f)\n", cols, rows, method,
                    dbl ? "double" : "float", grad ? "cost+gradient" : "cost only", ms,
                    cost / reps);
      }
    }
  }
  return 0;
}
