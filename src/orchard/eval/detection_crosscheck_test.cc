// Cross-check of EvaluateDetections against a second, independent
// implementation written here: a plain transcription of pycocotools'
// COCOeval (loadRes, computeIoU, evaluateImg, accumulate, summarize) on flat
// annotation lists with ids, as the Python code holds them, and of the study's
// per-frame protocol. Both are run on many random datasets (integer boxes, so
// IoUs hit thresholds exactly; few distinct scores, so ties are common; some
// images with more than 100 detections; mask areas unlike box areas).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>

#include "orchard/eval/detection_metrics.h"

namespace orchard {
namespace {

// ----- Reference COCOeval ----------------------------------------------------

struct RefGt {
  long image_id, id;
  double bbox[4];  // x, y, w, h
  double area;
};
struct RefDt {
  long image_id, id;
  double bbox[4];
  double score, area;
};

std::vector<double> NpLinspace(double start, double stop, int num) {
  std::vector<double> y(num);
  const double step = (stop - start) / (num - 1);
  for (int i = 0; i < num; ++i) y[i] = i * step + start;
  y[num - 1] = stop;
  return y;
}

// np.argsort(keys, kind='mergesort'): stable ascending.
template <typename T>
std::vector<int> ArgsortStable(const std::vector<T>& keys) {
  std::vector<int> idx(keys.size());
  for (size_t i = 0; i < idx.size(); ++i) idx[i] = static_cast<int>(i);
  std::sort(idx.begin(), idx.end(), [&](int a, int b) {
    if (keys[a] != keys[b]) return keys[a] < keys[b];
    return a < b;
  });
  return idx;
}

// maskApi.c bbIou, o[g*m+d] layout returned as ious[d][g].
std::vector<std::vector<double>> BbIou(const std::vector<const RefDt*>& dt,
                                       const std::vector<const RefGt*>& gt) {
  std::vector<std::vector<double>> o(dt.size(), std::vector<double>(gt.size(), 0));
  for (size_t g = 0; g < gt.size(); ++g) {
    const double* G = gt[g]->bbox;
    const double ga = G[2] * G[3];
    for (size_t d = 0; d < dt.size(); ++d) {
      const double* D = dt[d]->bbox;
      const double da = D[2] * D[3];
      const double w = std::fmin(D[2] + D[0], G[2] + G[0]) - std::fmax(D[0], G[0]);
      if (w <= 0) continue;
      const double h = std::fmin(D[3] + D[1], G[3] + G[1]) - std::fmax(D[1], G[1]);
      if (h <= 0) continue;
      const double i = w * h;
      o[d][g] = i / (da + ga - i);
    }
  }
  return o;
}

struct EvalImg {
  std::vector<double> dt_scores;
  std::vector<std::vector<double>> dt_matches;  // [T][D] matched gt id or 0
  std::vector<std::vector<bool>> dt_ignore;     // [T][D]
  std::vector<int> gt_ignore;
};

std::vector<double> ReferenceCocoStats(const std::vector<RefGt>& gts, const std::vector<RefDt>& dts,
                                       std::vector<long> img_ids) {
  const std::vector<double> iou_thrs = NpLinspace(0.5, 0.95, 10);
  const std::vector<double> rec_thrs = NpLinspace(0.0, 1.0, 101);
  const double area_rng[4][2] = {{0, 1e5 * 1e5}, {0, 32 * 32}, {32 * 32, 96 * 96}, {96 * 96, 1e5 * 1e5}};
  const size_t max_det = 100;
  std::sort(img_ids.begin(), img_ids.end());
  img_ids.erase(std::unique(img_ids.begin(), img_ids.end()), img_ids.end());

  std::map<long, std::vector<const RefGt*>> gts_of;
  std::map<long, std::vector<const RefDt*>> dts_of;
  for (const RefGt& g : gts) gts_of[g.image_id].push_back(&g);
  for (const RefDt& d : dts) dts_of[d.image_id].push_back(&d);

  // computeIoU
  std::map<long, std::vector<std::vector<double>>> ious_of;
  for (long img : img_ids) {
    auto gt = gts_of[img];
    auto dt = dts_of[img];
    if (gt.empty() && dt.empty()) continue;
    std::vector<double> neg;
    for (auto* d : dt) neg.push_back(-d->score);
    std::vector<const RefDt*> sorted;
    for (int i : ArgsortStable(neg)) sorted.push_back(dt[i]);
    if (sorted.size() > max_det) sorted.resize(max_det);
    if (sorted.empty() || gt.empty()) continue;  // maskUtils.iou -> []
    ious_of[img] = BbIou(sorted, gt);
  }

  // evaluateImg for each area range and image
  std::vector<std::vector<std::optional<EvalImg>>> eval_imgs(4);
  for (int a = 0; a < 4; ++a) {
    for (long img : img_ids) {
      auto gt = gts_of[img];
      auto dt = dts_of[img];
      if (gt.empty() && dt.empty()) {
        eval_imgs[a].push_back(std::nullopt);
        continue;
      }
      std::vector<int> ig;
      for (auto* g : gt) ig.push_back(g->area < area_rng[a][0] || g->area > area_rng[a][1]);
      const std::vector<int> gtind = ArgsortStable(ig);
      std::vector<const RefGt*> gt_s;
      std::vector<int> gt_ig;
      for (int i : gtind) {
        gt_s.push_back(gt[i]);
        gt_ig.push_back(ig[i]);
      }
      std::vector<double> neg;
      for (auto* d : dt) neg.push_back(-d->score);
      const std::vector<int> dtind = ArgsortStable(neg);
      std::vector<const RefDt*> dt_s;
      for (size_t k = 0; k < dtind.size() && k < max_det; ++k) dt_s.push_back(dt[dtind[k]]);
      const bool have_ious = ious_of.count(img) > 0;
      const size_t T = iou_thrs.size(), G = gt_s.size(), D = dt_s.size();
      std::vector<std::vector<double>> gtm(T, std::vector<double>(G, 0));
      std::vector<std::vector<double>> dtm(T, std::vector<double>(D, 0));
      std::vector<std::vector<bool>> dt_ig(T, std::vector<bool>(D, false));
      if (have_ious) {
        const auto& ious = ious_of[img];
        for (size_t t = 0; t < T; ++t) {
          for (size_t d = 0; d < D; ++d) {
            double iou = std::min(iou_thrs[t], 1 - 1e-10);
            int m = -1;
            for (size_t g = 0; g < G; ++g) {
              if (gtm[t][g] > 0) continue;
              if (m > -1 && gt_ig[m] == 0 && gt_ig[g] == 1) break;
              const double v = ious[d][gtind[g]];
              if (v < iou) continue;
              iou = v;
              m = static_cast<int>(g);
            }
            if (m == -1) continue;
            dt_ig[t][d] = gt_ig[m] != 0;
            dtm[t][d] = static_cast<double>(gt_s[m]->id);
            gtm[t][m] = static_cast<double>(dt_s[d]->id);
          }
        }
      }
      for (size_t t = 0; t < T; ++t) {
        for (size_t d = 0; d < D; ++d) {
          const bool outside = dt_s[d]->area < area_rng[a][0] || dt_s[d]->area > area_rng[a][1];
          dt_ig[t][d] = dt_ig[t][d] || (dtm[t][d] == 0 && outside);
        }
      }
      EvalImg e;
      for (auto* d : dt_s) e.dt_scores.push_back(d->score);
      e.dt_matches = dtm;
      e.dt_ignore = dt_ig;
      e.gt_ignore = gt_ig;
      eval_imgs[a].push_back(e);
    }
  }

  // accumulate: precision[a] = T x R, or empty (= all -1)
  std::vector<std::vector<std::vector<double>>> precision(4);
  for (int a = 0; a < 4; ++a) {
    std::vector<const EvalImg*> E;
    for (auto& e : eval_imgs[a]) {
      if (e) E.push_back(&*e);
    }
    if (E.empty()) continue;
    std::vector<double> scores;
    for (auto* e : E) {
      for (size_t k = 0; k < e->dt_scores.size() && k < max_det; ++k) scores.push_back(e->dt_scores[k]);
    }
    std::vector<double> neg;
    for (double s : scores) neg.push_back(-s);
    const std::vector<int> inds = ArgsortStable(neg);
    int npig = 0;
    for (auto* e : E) {
      for (int g : e->gt_ignore) npig += g == 0;
    }
    if (npig == 0) continue;
    precision[a].assign(iou_thrs.size(), std::vector<double>(rec_thrs.size(), 0));
    for (size_t t = 0; t < iou_thrs.size(); ++t) {
      std::vector<double> dtm_cat;
      std::vector<bool> dtig_cat;
      for (auto* e : E) {
        dtm_cat.insert(dtm_cat.end(), e->dt_matches[t].begin(), e->dt_matches[t].end());
        dtig_cat.insert(dtig_cat.end(), e->dt_ignore[t].begin(), e->dt_ignore[t].end());
      }
      std::vector<double> tp_sum, fp_sum;
      double tps = 0, fps = 0;
      for (int i : inds) {
        tps += (dtm_cat[i] != 0) && !dtig_cat[i];
        fps += (dtm_cat[i] == 0) && !dtig_cat[i];
        tp_sum.push_back(tps);
        fp_sum.push_back(fps);
      }
      const size_t nd = tp_sum.size();
      std::vector<double> rc(nd), pr(nd);
      for (size_t i = 0; i < nd; ++i) {
        rc[i] = tp_sum[i] / npig;
        pr[i] = tp_sum[i] / (fp_sum[i] + tp_sum[i] + 2.220446049250313e-16);
      }
      for (size_t i = nd - (nd > 0); i > 0; --i) {
        if (pr[i] > pr[i - 1]) pr[i - 1] = pr[i];
      }
      for (size_t ri = 0; ri < rec_thrs.size(); ++ri) {
        // np.searchsorted(rc, r, side='left'): first index with rc[i] >= r.
        size_t pi = 0;
        while (pi < nd && rc[pi] < rec_thrs[ri]) ++pi;
        if (pi >= nd) break;  // IndexError: the rest stay 0
        precision[a][t][ri] = pr[pi];
      }
    }
  }

  // summarize: stats[0..5]
  auto mean_of = [&](int a, int t_only) {
    if (precision[a].empty()) return -1.0;
    double sum = 0;
    int n = 0;
    for (size_t t = 0; t < precision[a].size(); ++t) {
      if (t_only >= 0 && static_cast<int>(t) != t_only) continue;
      for (double v : precision[a][t]) {
        if (v > -1) {
          sum += v;
          ++n;
        }
      }
    }
    return n == 0 ? -1.0 : sum / n;
  };
  int t50 = -1, t75 = -1;
  for (size_t t = 0; t < iou_thrs.size(); ++t) {
    if (iou_thrs[t] == 0.5) t50 = static_cast<int>(t);
    if (iou_thrs[t] == 0.75) t75 = static_cast<int>(t);
  }
  return {mean_of(0, -1), mean_of(0, t50), mean_of(0, t75),
          mean_of(1, -1), mean_of(2, -1), mean_of(3, -1)};
}

// ----- Reference study protocol ----------------------------------------------

double PlainIoU(const Box& a, const Box& b) {
  const double iw = std::min(a.x2, b.x2) - std::max(a.x1, b.x1);
  const double ih = std::min(a.y2, b.y2) - std::max(a.y1, b.y1);
  if (iw <= 0 || ih <= 0) return 0;
  const double inter = iw * ih;
  return inter / ((a.x2 - a.x1) * (a.y2 - a.y1) + (b.x2 - b.x1) * (b.y2 - b.y1) - inter);
}

// Returns [P(99), R(99), F1(99)].
std::vector<std::vector<double>> ReferenceStudy(const std::vector<std::vector<Box>>& gt,
                                                const std::vector<std::vector<ScoredBox>>& pred) {
  std::vector<std::vector<double>> out(3, std::vector<double>(99, 0));
  for (size_t f = 0; f < gt.size(); ++f) {
    std::vector<int> order(pred[f].size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
    std::sort(order.begin(), order.end(), [&](int a, int b) {
      if (pred[f][a].score != pred[f][b].score) return pred[f][a].score > pred[f][b].score;
      return a < b;
    });
    for (int i = 1; i <= 99; ++i) {
      const double t = i / 100.0;
      std::set<size_t> matched;
      int tp = 0;
      for (int p : order) {
        std::vector<double> cand(gt[f].size(), -1.0);
        for (size_t g = 0; g < gt[f].size(); ++g) {
          const double v = PlainIoU(pred[f][p].box, gt[f][g]);
          if (!matched.count(g) && v >= t) cand[g] = v;
        }
        if (cand.empty()) continue;
        const auto best = std::max_element(cand.begin(), cand.end());
        if (*best < 0) continue;
        matched.insert(best - cand.begin());
        ++tp;
      }
      const double P = pred[f].empty() ? 1.0 : double(tp) / pred[f].size();
      const double R = gt[f].empty() ? 1.0 : double(tp) / gt[f].size();
      const double F = (P + R) == 0 ? 0.0 : 2 * P * R / (P + R);
      out[0][i - 1] += P / gt.size();
      out[1][i - 1] += R / gt.size();
      out[2][i - 1] += F / gt.size();
    }
  }
  return out;
}

// ----- Random datasets ---------------------------------------------------------

struct RandomCase {
  Dataset dataset;
  Predictions predictions;
};

RandomCase MakeRandomCase(std::mt19937& rng) {
  auto uni = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
  RandomCase c;
  const int num_images = uni(1, 7);
  std::vector<long> ids(num_images);
  for (int i = 0; i < num_images; ++i) ids[i] = 10 + 3 * i;
  std::shuffle(ids.begin(), ids.end(), rng);  // image ids not in name order
  c.dataset.has_masks = uni(0, 1) == 1;
  for (int i = 0; i < num_images; ++i) {
    AnnotatedImage image;
    image.name = "im" + std::to_string(i) + ".png";
    image.id = ids[i];
    image.width = image.height = 200;
    const int num_gt = uni(0, 2) == 0 ? 0 : uni(1, 12);
    for (int k = 0; k < num_gt; ++k) {
      Annotation a;
      const int size = uni(0, 5) == 0 ? uni(90, 140) : uni(2, 60);
      const int x = uni(-5, 150), y = uni(0, 150);  // some boxes leave the image
      a.box = {double(x), double(y), double(x + size), double(y + uni(std::max(2, size / 2), size))};
      if (c.dataset.has_masks) a.area = std::floor(a.box.Area() * uni(30, 100) / 100.0);
      image.objects.push_back(a);
    }
    std::vector<ScoredBox> preds;
    const int many = uni(0, 9) == 0 ? 101 + uni(0, 10) : 0;  // sometimes > maxDets
    for (const Annotation& a : image.objects) {
      for (int copies = uni(0, 2); copies > 0; --copies) {
        ScoredBox p;
        const double j = uni(0, 3) == 0 ? 0.5 : 1.0;  // half-pixel jitter sometimes
        p.box = {a.box.x1 + j * uni(-4, 4), a.box.y1 + j * uni(-4, 4), a.box.x2 + j * uni(-4, 4),
                 a.box.y2 + j * uni(-4, 4)};
        if (p.box.x2 <= p.box.x1 || p.box.y2 <= p.box.y1) p.box = a.box;
        p.score = uni(1, 10) / 10.0;  // few distinct scores: many ties
        preds.push_back(p);
      }
    }
    for (int k = uni(0, 4) + many; k > 0; --k) {
      const int x = uni(0, 180), y = uni(0, 180), s = uni(1, 100);
      preds.push_back({Box{double(x), double(y), double(x + s), double(y + s)},
                       uni(0, 1) ? uni(1, 10) / 10.0 : uni(0, 1000000) / 1e6});
    }
    std::shuffle(preds.begin(), preds.end(), rng);
    if (!preds.empty() || uni(0, 3) == 0) {
      c.predictions[uni(0, 1) ? image.name : "im" + std::to_string(i)] = preds;
    }
    c.dataset.images.push_back(image);
  }
  return c;
}

TEST(DetectionCrossCheck, RandomDatasetsAgreeWithReferenceImplementations) {
  std::mt19937 rng(12345);
  int compared_nontrivial = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const RandomCase c = MakeRandomCase(rng);
    const DetectionMetrics m = EvaluateDetections(c.dataset, c.predictions);

    // Reference inputs: COCO-style flat lists (loadRes gives dt ids 1.. and
    // area w*h), frames in dataset order for the study protocol.
    std::vector<RefGt> gts;
    std::vector<RefDt> dts;
    std::vector<long> img_ids;
    std::vector<std::vector<Box>> frame_gt;
    std::vector<std::vector<ScoredBox>> frame_pred;
    long next_gt = 1, next_dt = 1;
    for (const AnnotatedImage& image : c.dataset.images) {
      img_ids.push_back(image.id);
      frame_gt.emplace_back();
      for (const Annotation& a : image.objects) {
        const double w = a.box.x2 - a.box.x1, h = a.box.y2 - a.box.y1;
        gts.push_back({image.id, next_gt++, {a.box.x1, a.box.y1, w, h}, a.area >= 0 ? a.area : w * h});
        frame_gt.back().push_back(a.box);
      }
      frame_pred.emplace_back();
      for (const auto& [name, boxes] : c.predictions) {
        if (name != image.name && name + ".png" != image.name) continue;
        for (const ScoredBox& p : boxes) {
          const double w = p.box.x2 - p.box.x1, h = p.box.y2 - p.box.y1;
          dts.push_back({image.id, next_dt++, {p.box.x1, p.box.y1, w, h}, p.score, w * h});
        }
        frame_pred.back() = boxes;
      }
    }
    const std::vector<double> ref = ReferenceCocoStats(gts, dts, img_ids);
    const double got[6] = {m.coco.ap, m.coco.ap50, m.coco.ap75, m.coco.aps, m.coco.apm, m.coco.apl};
    for (int k = 0; k < 6; ++k) {
      ASSERT_NEAR(got[k], ref[k], 1e-6) << "trial " << trial << " stat " << k;
    }
    if (ref[0] > 0 && ref[0] < 1) ++compared_nontrivial;

    const auto study = ReferenceStudy(frame_gt, frame_pred);
    for (int t = 0; t < 99; ++t) {
      ASSERT_NEAR(m.curve.precision[t], study[0][t], 1e-6) << "trial " << trial << " t " << t;
      ASSERT_NEAR(m.curve.recall[t], study[1][t], 1e-6) << "trial " << trial << " t " << t;
      ASSERT_NEAR(m.curve.f1[t], study[2][t], 1e-6) << "trial " << trial << " t " << t;
    }
  }
  // The random cases must exercise the interesting range, not only 0 and 1.
  EXPECT_GT(compared_nontrivial, 200);
}

}  // namespace
}  // namespace orchard
