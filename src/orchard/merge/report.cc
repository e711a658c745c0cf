#include "orchard/merge/report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace orchard {
namespace {

std::string Escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else if (c == '&') out += "&amp;";
    else if (c == '"') out += "&quot;";
    else out += c;
  }
  return out;
}

std::string Num(double v, int decimals = 1) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

std::string Percent(double estimate, double truth) {
  return truth > 0 ? Num(100.0 * estimate / truth) + "%" : "-";
}

// yield.json's sides.<side>.<key>, front then back, for the sides that have it.
std::vector<std::pair<std::string, const nlohmann::json*>> SidesWith(const nlohmann::json& y, const char* key) {
  std::vector<std::pair<std::string, const nlohmann::json*>> sides;
  if (!y.contains("sides")) return sides;
  for (const char* side : {"front", "back"})
    if (y.at("sides").contains(side) && y.at("sides").at(side).contains(key))
      sides.emplace_back(side, &y.at("sides").at(side).at(key));
  return sides;
}

// Each side's count against the generator's truth (sides.<side>.truth, when
// the sides were scored): the apples found and missed, and the rest of the
// count; empty when neither side was scored.
std::string SideTruthTable(const nlohmann::json& y) {
  const auto sides = SidesWith(y, "truth");
  if (sides.empty()) return "";
  std::ostringstream h;
  h << "<h2>Where each side's count comes from</h2>\n<p>Against the generator's truth: every kept cluster credited "
       "with the visible apples its fruit points land on, up to its count. Apples seen in one or two frames cannot be "
       "placed by any multi-view rule.</p>\n<table><tr><th></th>";
  for (const auto& [name, t] : sides) h << "<th>" << name << "</th>";
  h << "</tr>\n";
  // The apples seen in at most two views, of a by-views histogram.
  const auto glimpsed = [](const nlohmann::json& t, const char* key) {
    if (!t.contains(key)) return std::string("-");
    const auto bins = t.at(key).get<std::vector<int>>();
    int n = 0;
    for (size_t i = 0; i < bins.size() && i <= 2; ++i) n += bins[i];
    return std::to_string(n);
  };
  const auto row = [&](const std::string& label, const auto& cell) {
    h << "<tr><td>" << Escape(label) << "</td>";
    for (const auto& [name, t] : sides) h << "<td>" << cell(*t) << "</td>";
    h << "</tr>\n";
  };
  const auto number = [](const char* key) {
    return [key](const nlohmann::json& t) { return std::to_string(t.value(key, 0)); };
  };
  row("apples visible from the side", number("visible"));
  row("counted", [](const nlohmann::json& t) {
    const int visible = t.value("visible", 0), count = t.value("count", 0);
    return std::to_string(count) + (visible > 0 ? " (" + Num(100.0 * (count - visible) / visible) + "%)" : "");
  });
  row("visible apples found", number("found"));
  row("visible apples missed", number("missed"));
  row("... of them seen in at most two frames", [&](const nlohmann::json& t) {
    return glimpsed(t, "missed_by_views_seen") + " of " + glimpsed(t, "visible_by_views_seen");
  });
  row("counted twice (a cluster on an apple another holds)", number("duplicates"));
  row("counted above the apples a cluster holds", number("over_counted"));
  row("on no visible apple (next row, fallen, chance)", number("not_visible"));
  h << "</table>\n";
  return h.str();
}

// The merged count taken apart against the generator's truth (truth.merge,
// when both sides were scored); empty otherwise.
std::string MergeTruthTable(const nlohmann::json& y) {
  if (!y.contains("truth") || !y.at("truth").contains("merge")) return "";
  const nlohmann::json& m = y.at("truth").at("merge");
  const int visible = m.value("visible_any", 0), total = y.value("total", 0);
  const double shared = m.value("shared", 0.0);
  const int linked = m.value("linked", 0);
  std::ostringstream h;
  h << "<h2>Where the merged count comes from</h2>\n<p>The clusters each side keeps for the merge, credited with the "
       "visible apples their fruit points land on. The merged count's error is the sum of the signed terms.</p>\n"
       "<table><tr><th></th><th>apples</th></tr>\n";
  const auto row = [&](const std::string& label, const std::string& value) {
    h << "<tr><td>" << Escape(label) << "</td><td>" << value << "</td></tr>\n";
  };
  const auto signed_number = [](double v) { return (v >= 0 ? "+" : "") + Num(v, 0); };
  row("visible from either side (from both)",
      std::to_string(visible) + " (" + std::to_string(m.value("visible_both", 0)) + ")");
  row("merged count", std::to_string(total) + " (" + signed_number(total - visible) + ")");
  row("front clusters counted above the apples they hold", signed_number(m.value("extra_front", 0)));
  row("back clusters counted above the apples they hold", signed_number(m.value("extra_back", 0)));
  row("apples held by neither side", signed_number(-m.value("held_by_neither", 0)));
  row("apples both sides hold in clusters not linked (counted twice)", signed_number(m.value("unlinked", 0)));
  row("apples both sides hold in linked clusters (" + std::to_string(linked) + ") less those counted once (" +
          Num(shared, 0) + ")",
      signed_number(linked - shared));
  h << "</table>\n";
  return h.str();
}

// Apples along the row (x) and by height (y), and the per-metre bars below.
std::string MapSvg(const nlohmann::json& y, const std::vector<MapCluster>& clusters) {
  double x0 = 0, x1 = 1, h1 = 3;
  if (!clusters.empty()) {
    x0 = x1 = clusters[0].along;
    for (const auto& c : clusters) x0 = std::min(x0, c.along), x1 = std::max(x1, c.along), h1 = std::max(h1, c.height);
  }
  for (const auto& b : y.at("per_metre")) x0 = std::min(x0, b.at("from").get<double>()), x1 = std::max(x1, b.at("to").get<double>());
  // Where each side's frames end at the row: fruit above it is in no frame.
  std::vector<std::pair<std::string, double>> tops;
  for (const auto& [side, reach] : SidesWith(y, "frames_reach")) {
    tops.emplace_back(side, reach->at("top_m").get<double>());
    h1 = std::max(h1, tops.back().second);
  }
  const double width = 900, map_h = 300, bar_h = 120, pad = 40;
  const double sx = (width - 2 * pad) / std::max(x1 - x0, 1e-6), sy = (map_h - 2 * pad) / h1;
  std::ostringstream s;
  s << "<svg xmlns='http://www.w3.org/2000/svg' width='" << width << "' height='" << map_h + bar_h + 30
    << "' style='background:#fbfbf7;border:1px solid #ccc'>\n";
  // Ground line and height ticks.
  s << "<line x1='" << pad << "' y1='" << map_h - pad << "' x2='" << width - pad << "' y2='" << map_h - pad
    << "' stroke='#7a5' stroke-width='2'/>\n";
  for (int m = 0; m <= static_cast<int>(h1); ++m)
    s << "<text x='4' y='" << map_h - pad - m * sy + 4 << "' font-size='11'>" << m << " m</text>\n";
  for (size_t i = 0; i < tops.size(); ++i) {
    const std::string colour = tops[i].first == "front" ? "#2a7" : "#27c";
    const double ty = map_h - pad - tops[i].second * sy;
    s << "<line x1='" << pad << "' y1='" << Num(ty) << "' x2='" << width - pad << "' y2='" << Num(ty) << "' stroke='"
      << colour << "' stroke-dasharray='6,4'/>\n";
    s << "<text x='" << Num(width - pad - 230) << "' y='" << Num(ty - 3 - 12 * static_cast<double>(i)) << "' font-size='11' fill='"
      << colour << "'>" << tops[i].first << " frames' top edge at the row</text>\n";
  }
  // The trunks found (per_tree), from the ground to 0.5 m.
  if (y.contains("per_tree"))
    for (const auto& t : y.at("per_tree")) {
      const double tx = pad + (t.at("along_m").get<double>() - x0) * sx;
      s << "<line x1='" << Num(tx) << "' y1='" << map_h - pad << "' x2='" << Num(tx) << "' y2='"
        << Num(map_h - pad - 0.5 * sy) << "' stroke='#753' stroke-width='4'><title>tree " << t.at("tree").get<int>()
        << "</title></line>\n";
    }
  for (const auto& c : clusters) {
    const std::string colour = c.shared > 0 ? "#d22" : (c.side == "front" ? "#2a7" : "#27c");
    s << "<circle cx='" << Num(pad + (c.along - x0) * sx) << "' cy='" << Num(map_h - pad - c.height * sy) << "' r='"
      << Num(3 + 1.5 * std::sqrt(std::max(c.count, 0))) << "' fill='" << colour << "' fill-opacity='0.6'><title>"
      << c.side << ": " << c.count << " apple(s)" << (c.shared > 0 ? ", " + Num(c.shared) + " seen from both sides" : "")
      << "</title></circle>\n";
  }
  // Per-metre bars: calibrated apples when the run was calibrated, else those seen.
  const bool calibrated = y.contains("calibrated");
  const char* bar_key = calibrated ? "calibrated" : "count";
  double most = 1;
  for (const auto& b : y.at("per_metre")) most = std::max(most, b.value(bar_key, 0.0));
  const double base = map_h + bar_h;
  for (const auto& b : y.at("per_metre")) {
    const double from = b.at("from").get<double>(), to = b.at("to").get<double>(), n = b.value(bar_key, 0.0);
    const double h = (bar_h - 20) * n / most;
    s << "<rect x='" << Num(pad + (from - x0) * sx + 1) << "' y='" << Num(base - h) << "' width='"
      << Num(std::max((to - from) * sx - 2, 1.0)) << "' height='" << Num(h) << "' fill='#c84'/>\n";
    s << "<text x='" << Num(pad + ((from + to) / 2 - x0) * sx - 8) << "' y='" << Num(base - h - 3)
      << "' font-size='11'>" << Num(n, 0) << "</text>\n";
    s << "<text x='" << Num(pad + (from - x0) * sx) << "' y='" << base + 14 << "' font-size='11'>" << Num(from)
      << " m</text>\n";
  }
  s << "<text x='" << pad << "' y='14' font-size='12'>apples along the row (front side's frame): "
       "<tspan fill='#2a7'>front</tspan>, <tspan fill='#27c'>back</tspan>, <tspan fill='#d22'>seen from both sides</tspan>; "
       "bars: "
    << (calibrated ? "calibrated apples" : "apples") << " per bin</text>\n";
  s << "</svg>\n";
  return s.str();
}

}  // namespace

std::string YieldReportHtml(const nlohmann::json& y, const std::vector<MapCluster>& clusters,
                            const std::vector<std::string>& frames) {
  std::ostringstream h;
  h << "<!DOCTYPE html>\n<html><head><meta charset='utf-8'><title>orchard yield</title>\n"
       "<style>body{font-family:sans-serif;max-width:960px;margin:2em auto;color:#222}"
       "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #ccc;padding:4px 10px;text-align:right}"
       "th{background:#eee}td:first-child{text-align:left}img{max-width:440px;margin:4px;border:1px solid #ccc}"
       ".warn{color:#a40}</style></head><body>\n";
  h << "<h1>Apple yield of the row: " << y.at("total").get<int>() << " apples";
  if (y.contains("calibrated")) h << " seen, " << y.at("calibrated").at("total").get<int>() << " calibrated";
  h << "</h1>\n";
  h << "<p>Two videos, one from each side of the row, each reconstructed in 3D; fruit clusters counted once per side "
       "from their best views; the sides aligned on the ground plane and their shared fruit; apples seen from both "
       "sides counted once (inclusion-exclusion).</p>\n";
  const auto& t = y.contains("truth") ? y.at("truth") : nlohmann::json();
  h << "<h2>Counts</h2>\n<table><tr><th></th><th>apples</th>";
  if (!t.is_null()) h << "<th>of harvested</th><th>of visible from either side</th>";
  h << "</tr>\n";
  auto row = [&](const std::string& name, double v) {
    h << "<tr><td>" << Escape(name) << "</td><td>" << Num(v, 0) << "</td>";
    if (!t.is_null())
      h << "<td>" << Percent(v, t.value("harvested", 0.0)) << "</td><td>" << Percent(v, t.value("visible_any", 0.0))
        << "</td>";
    h << "</tr>\n";
  };
  row("estimate (both sides merged)", y.at("total").get<double>());
  if (y.contains("calibrated")) {
    const auto& c = y.at("calibrated");
    const int runs = c.at("runs").get<int>();
    std::string name = "calibrated on " + std::to_string(runs) + (runs == 1 ? " harvested row" : " harvested rows") +
                       " (x" + Num(c.at("factor").get<double>(), 3) + ")";
    if (c.contains("leave_one_out_mean_absolute_error_percent"))
      name += ", expected error " + Num(c.at("leave_one_out_mean_absolute_error_percent").get<double>(), 1) + "%";
    row(name, c.at("total").get<double>());
  }
  row("front side", y.at("front").get<double>());
  row("back side", y.at("back").get<double>());
  row("sum of the sides, not merged", y.at("sum_of_sides").get<double>());
  row("seen from both sides (subtracted)", y.at("shared").get<double>());
  if (!t.is_null()) {
    row("truth: harvested", t.value("harvested", 0.0));
    row("truth: visible from either side", t.value("visible_any", 0.0));
    row("truth: visible from both sides", t.value("visible_both", 0.0));
  }
  h << "</table>\n";
  h << SideTruthTable(y) << MergeTruthTable(y);
  for (const auto& w : y.at("warnings")) h << "<p class='warn'>Warning: " << Escape(w.get<std::string>()) << "</p>\n";
  if (y.contains("sides")) {  // where each side's camera poses came from
    std::string poses;
    for (const char* side : {"front", "back"}) {
      if (!y.at("sides").contains(side)) continue;
      const nlohmann::json& s = y.at("sides").at(side);
      poses += std::string(poses.empty() ? "" : "; ") + side + ": " + s.value("poses", std::string("?")) + ", " +
               std::to_string(s.value("frames_used", 0)) + " frames used";
    }
    h << "<p>Poses: " << Escape(poses) << ".</p>\n";
    // What the frames cut off is counted by no method (docs/yield.md).
    std::string reach;
    for (const auto& [side, r] : SidesWith(y, "frames_reach"))
      reach += std::string(reach.empty() ? "" : "; ") + side + " " + Num(r->at("bottom_m").get<double>(), 2) + "-" +
               Num(r->at("top_m").get<double>(), 2) + " m above the ground, " +
               Num(r->at("at_distance_m").get<double>(), 2) + " m from the camera path";
    if (!reach.empty())
      h << "<p>The frames reach the row: " << Escape(reach)
        << ". Apples hanging above the frames' top edge are in no frame and not counted; where the canopy is taller, "
           "film with its top in the frame (a taller frame, a higher or level camera).</p>\n";
  }
  h << "<h2>Map</h2>\n" << MapSvg(y, clusters);
  if (y.contains("per_tree") && !y.at("per_tree").empty()) {
    const bool calibrated_trees = y.contains("calibrated");
    // The generator's trees, when the truth was given and the counts of trees agree.
    const nlohmann::json* true_trees =
        y.contains("truth") && y.at("truth").contains("per_tree") ? &y.at("truth").at("per_tree") : nullptr;
    h << "<h2>Per tree</h2>\n<p>Trunks found in the sparse points (brown on the map); each tree holds the apples "
         "between the midpoints to its neighbours.</p>\n<table><tr><th>tree</th><th>along the row</th><th>trunk seen "
         "from</th><th>apples</th>"
      << (calibrated_trees ? "<th>calibrated</th>" : "")
      << (true_trees ? "<th>visible (truth)</th><th>of visible</th><th>harvested (truth)</th>" : "") << "</tr>\n";
    size_t k = 0;
    for (const auto& t : y.at("per_tree")) {
      h << "<tr><td>" << t.at("tree").get<int>() << "</td><td>" << Num(t.at("along_m").get<double>(), 2)
        << " m</td><td>" << Escape(t.at("trunk_seen_from").get<std::string>()) << "</td><td>"
        << Num(t.at("count").get<double>(), 0) << "</td>";
      if (calibrated_trees) h << "<td>" << Num(t.value("calibrated", 0.0), 0) << "</td>";
      if (true_trees && k < true_trees->size()) {
        const auto& tt = (*true_trees)[k];
        h << "<td>" << Num(tt.at("visible_any").get<double>(), 0) << "</td><td>"
          << (tt.contains("percent_of_visible_any") ? Num(tt.at("percent_of_visible_any").get<double>()) + "%" : "-")
          << "</td><td>" << Num(tt.at("harvested").get<double>(), 0) << "</td>";
      }
      h << "</tr>\n";
      ++k;
    }
    h << "<tr><td>outside the trees</td><td></td><td></td><td>" << Num(y.value("per_tree_outside", 0.0), 0)
      << "</td>" << (calibrated_trees ? "<td></td>" : "") << (true_trees ? "<td></td><td></td><td></td>" : "")
      << "</tr></table>\n";
    if (true_trees && y.at("truth").contains("per_tree_mean_abs_error_percent"))
      h << "<p>Per-tree error against the visible apples of each tree (the generator's trees in order along the row): "
        << Num(y.at("truth").at("per_tree_mean_abs_error_percent").get<double>()) << "% on average.</p>\n";
    else if (y.contains("truth") && y.at("truth").contains("per_tree_note"))
      h << "<p>" << Escape(y.at("truth").at("per_tree_note").get<std::string>()) << "</p>\n";
  }
  const auto& a = y.at("alignment");
  h << "<h2>Alignment of the two sides</h2>\n<table>"
    << "<tr><td>method</td><td>" << Escape(a.at("method").get<std::string>()) << "</td></tr>"
    << "<tr><td>heading (beyond facing each other)</td><td>" << Num(a.at("heading_deg").get<double>(), 2) << "&deg;</td></tr>"
    << "<tr><td>offset along the row</td><td>" << Num(a.at("along_m").get<double>(), 3) << " m</td></tr>"
    << "<tr><td>distance between the camera paths</td><td>" << Num(a.at("across_m").get<double>(), 3) << " m</td></tr>"
    << "<tr><td>clusters matched across the sides (of them fallen apples)</td><td>" << a.at("matched").get<int>()
    << " (" << a.value("matched_fallen", 0) << ")</td></tr>"
    << "<tr><td>residual (RMS distance of matched clusters)</td><td>" << Num(100 * a.at("residual_m").get<double>(), 1)
    << " cm</td></tr>"
    << "<tr><td>best match count of any other alignment</td><td>" << a.at("chance_matched").get<int>() << "</td></tr>"
    << "<tr><td>overlap along the row</td><td>" << Num(a.at("overlap_m").get<double>(), 2) << " m</td></tr>";
  if (a.contains("across_from"))
    h << "<tr><td>distance across from</td><td>" << Escape(a.at("across_from").get<std::string>()) << "</td></tr>";
  if (a.contains("trunks")) {
    const auto& t = a.at("trunks");
    h << "<tr><td>trunks found in the sparse points (front / back)</td><td>" << t.at("front").get<int>() << " / "
      << t.at("back").get<int>();
    if (t.contains("across_m")) h << "; they put the camera paths " << Num(t.at("across_m").get<double>(), 3) << " m apart";
    h << "</td></tr>";
  }
  h << "</table>\n";
  if (!frames.empty()) {
    h << "<h2>Sample frames</h2>\n<p>Each 3D cluster's region outlined with its count; grey: removed (fallen apples, "
         "the next row, ...).</p>\n";
    for (const auto& f : frames) h << "<a href='" << Escape(f) << "'><img src='" << Escape(f) << "' alt='" << Escape(f) << "'></a>\n";
  }
  h << "<h2>Timings</h2>\n<table><tr><th>stage</th><th>seconds</th></tr>\n";
  for (const auto& [stage, seconds] : y.at("timings_s").items())
    h << "<tr><td>" << Escape(stage) << "</td><td>" << Num(seconds.get<double>(), 1) << "</td></tr>\n";
  h << "</table>\n<h2>Settings</h2>\n<pre>" << Escape(y.at("settings").dump(2)) << "</pre>\n";
  h << "</body></html>\n";
  return h.str();
}

}  // namespace orchard
