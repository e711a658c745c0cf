#include "orchard/detect/parallel_detection.h"

#include <atomic>
#include <condition_variable>
#include <exception>
#include <limits>
#include <mutex>
#include <thread>

#include "orchard/core/error.h"

namespace orchard {

void DetectFrames(const std::vector<std::unique_ptr<Detector>>& detectors, const FrameReader& read,
                  const DetectionSink& sink) {
  if (detectors.empty()) Fail("no detector to run");
  std::mutex read_mutex, order_mutex;
  std::condition_variable turn;
  long next_read = 0;  // guarded by read_mutex
  bool ended = false;  // guarded by read_mutex
  long next_sink = 0;  // guarded by order_mutex
  // The first frame that failed (read, detected or sunk): frames before it are
  // still handed over, frames after it are not. Written under order_mutex.
  std::atomic<long> stop_at{std::numeric_limits<long>::max()};
  std::exception_ptr error;  // the error of frame stop_at; guarded by order_mutex
  auto fail = [&](long seq) {
    std::lock_guard<std::mutex> lock(order_mutex);
    if (seq < stop_at) stop_at = seq, error = std::current_exception();
    turn.notify_all();
  };
  auto work = [&](Detector* detector) {
    for (;;) {
      Frame frame;
      long seq = 0;
      {
        std::lock_guard<std::mutex> lock(read_mutex);
        seq = next_read;
        if (ended || seq >= stop_at) return;
        try {
          if (!read(&frame)) {
            ended = true;
            return;
          }
        } catch (...) {
          fail(seq);
          return;
        }
        ++next_read;
      }
      try {
        FrameDetection detection = detector->Detect(frame.image);
        {
          std::unique_lock<std::mutex> lock(order_mutex);
          turn.wait(lock, [&] { return next_sink == seq || seq >= stop_at; });
          if (seq >= stop_at) return;
        }
        sink(frame, detection);  // only this thread has next_sink == seq
        std::lock_guard<std::mutex> lock(order_mutex);
        ++next_sink;
        turn.notify_all();
      } catch (...) {
        fail(seq);
        return;
      }
    }
  };
  if (detectors.size() == 1) {
    work(detectors[0].get());
  } else {
    std::vector<std::thread> threads;
    for (const auto& d : detectors) threads.emplace_back(work, d.get());
    for (std::thread& t : threads) t.join();
  }
  if (error) std::rethrow_exception(error);
}

}  // namespace orchard
