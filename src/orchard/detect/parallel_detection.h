// Detection of a stream of frames, several frames at once: the colour
// detector's steps are short and partly serial, so two frames on two cores
// (one detector each, single-threaded) go 1.5-2x faster than one frame split
// over both cores. Results are handed over in frame order.
#pragma once

#include <functional>
#include <memory>
#include <vector>

#include "orchard/core/frame_source.h"
#include "orchard/detect/detector.h"

namespace orchard {

// The next frame; false at the end. Called by one thread at a time, in order.
using FrameReader = std::function<bool(Frame*)>;
// Receives each frame with its detection, in the order the reader gave them,
// one call at a time.
using DetectionSink = std::function<void(Frame& frame, FrameDetection& detection)>;

// Runs detectors[i] on its own thread (a detector is never shared between
// threads), each taking the next frame from `read` as soon as it is free; at
// most detectors.size() frames are in memory. An exception thrown by the
// reader, a detector or the sink stops the run: every frame before the failed
// one is still handed to the sink, none after it, and the failed frame's
// exception is rethrown here once every thread has finished.
void DetectFrames(const std::vector<std::unique_ptr<Detector>>& detectors, const FrameReader& read,
                  const DetectionSink& sink);

}  // namespace orchard
