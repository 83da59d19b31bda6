#include <paco/evaluation/report.h>

#include <paco/common/error.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <set>
#include <sstream>

namespace paco::evaluation {

namespace {

const std::vector<std::pair<FailureReason, const char*>>& reasonNames() {
  static const std::vector<std::pair<FailureReason, const char*>> names = {
      {FailureReason::None, "none"},          {FailureReason::NoMesh, "no-mesh"},
      {FailureReason::EmptyMesh, "empty"},    {FailureReason::NotClosed, "not-closed"},
      {FailureReason::NotManifold, "not-manifold"}, {FailureReason::NotOriented, "not-oriented"},
      {FailureReason::TimeLimit, "time-limit"}, {FailureReason::Threw, "threw"},
      {FailureReason::Sanity, "sanity"}};
  return names;
}

std::string formatNumber(double value, int precision = 6) {
  if (std::isnan(value)) return "";
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.*g", precision, value);
  return buffer;
}

std::string quote(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string q = "\"";
  for (char c : text) {
    if (c == '"') q += "\"\"";
    else if (c == '\n' || c == '\r') q += ' ';
    else q += c;
  }
  return q + "\"";
}

// Splits one CSV line (RFC 4180 quoting, no embedded newlines). Returns false on an unclosed quote.
bool splitCsv(const std::string& line, std::vector<std::string>& fields) {
  fields.clear();
  std::string field;
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') { field += '"'; ++i; }
      else if (c == '"') quoted = false;
      else field += c;
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      fields.push_back(field);
      field.clear();
    } else {
      field += c;
    }
  }
  fields.push_back(field);
  return !quoted;
}

double parseNumber(const std::string& text) {
  if (text.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::size_t used = 0;
  const double v = std::stod(text, &used);
  if (used != text.size()) throw std::invalid_argument("trailing characters");
  return v;
}

// CD, HD and NC: every case has them, failed ones their failure-box scores; a row without them
// is malformed, and would make every mean it joins NaN.
double parseFiniteNumber(const std::string& text) {
  const double v = parseNumber(text);
  if (!std::isfinite(v)) throw std::invalid_argument("not a finite number");
  return v;
}

const char* kFixedColumns[] = {"method", "assembler", "part", "level", "view", "status", "reason",
                               "cd", "hd", "nc", "nc_prim", "unmatched_pred", "faces", "vertices",
                               "closed", "volume_ratio", "cd_pred_to_gt", "cd_gt_to_pred",
                               "hidden_fraction", "cd_gt_to_pred_seen", "cd_gt_to_pred_hidden", "nc_pred_to_gt",
                               "nc_gt_to_pred", "nc_gt_to_pred_seen", "nc_gt_to_pred_hidden"};
constexpr std::size_t kNumFixed = sizeof(kFixedColumns) / sizeof(kFixedColumns[0]);

double mean(const std::vector<double>& v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  double s = 0.0;
  for (double x : v) s += x;
  return s / static_cast<double>(v.size());
}

double median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Linear interpolation between the closest ranks (q in [0, 1]).
double percentile(std::vector<double> v, double q) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  const double position = q * static_cast<double>(v.size() - 1);
  const std::size_t below = static_cast<std::size_t>(position);
  const std::size_t above = std::min(below + 1, v.size() - 1);
  return v[below] + (position - static_cast<double>(below)) * (v[above] - v[below]);
}

std::string cell(double value, int decimals) {
  if (std::isnan(value) || value < -0.5) return "–";
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.*f", decimals, value);
  return buffer;
}

const char* levelName(int level) {
  switch (level) {
    case 0: return "Simple (25 % missing)";
    case 1: return "Moderate (50 % missing)";
    case 2: return "Hard (75 % missing)";
    default: return "Level";
  }
}

// The rows of a table: records grouped by (method, assembler) in order of first appearance, and
// the stages (in stageNames() order, except `left_out`) that any of them timed.
struct Rows {
  std::vector<std::pair<std::string, std::string>> order;
  std::map<std::pair<std::string, std::string>, std::vector<EvaluationRecord>> groups;
  std::vector<std::string> stages;
};

Rows groupRows(const std::vector<EvaluationRecord>& records, bool with_sanity, const std::string& left_out) {
  Rows rows;
  std::set<std::string> stages_seen;
  for (const auto& r : records) {
    if (!with_sanity && r.method == "sanity") continue;
    const auto k = std::make_pair(r.method, r.assembler);
    if (!rows.groups.count(k)) rows.order.push_back(k);
    rows.groups[k].push_back(r);
    for (const auto& [stage, t] : r.seconds)
      if (stage != left_out) stages_seen.insert(stage);
  }
  for (const auto& s : stageNames())
    if (stages_seen.count(s)) rows.stages.push_back(s);
  return rows;
}

// "seen / hidden (hidden %)", or "–" when no case measured the split.
std::string seenHidden(const Summary& s) {
  if (s.hidden_fraction < 0.0) return "–";
  return cell(s.chamfer_gt_to_pred_seen, 2) + " / " + cell(s.chamfer_gt_to_pred_hidden, 2) + " (" +
         cell(100.0 * s.hidden_fraction, 0) + ")";
}

// NC's "pred→GT / GT→pred (GT→pred seen / hidden)", the split when measured.
std::string ncHalves(const Summary& s) {
  std::string text = cell(s.nc_pred_to_gt, 3) + " / " + cell(s.nc_gt_to_pred, 3);
  if (s.hidden_fraction >= 0.0)
    text += " (" + cell(s.nc_gt_to_pred_seen, 3) + " / " + cell(s.nc_gt_to_pred_hidden, 3) + ")";
  return text;
}

std::string table(const std::vector<EvaluationRecord>& records) {
  // Rows in order of first appearance of (method, assembler); sanity last. "total" has its own column.
  Rows rows = groupRows(records, /*with_sanity=*/true, "total");
  auto& order = rows.order;
  auto& groups = rows.groups;
  const auto& stages = rows.stages;
  std::stable_partition(order.begin(), order.end(), [](const auto& k) { return k.first != "sanity"; });

  std::ostringstream md;
  md << "| Method | Assembler | N | FR % | CD | CD pred→GT / GT→pred | GT→pred seen / hidden (hidden %) | HD | NC | NC pred→GT / GT→pred (seen / hidden) | NC_prim | unmatched pred | CD closed | HD closed | "
        "vol. ratio (median) | #f | #v | failures by reason |";
  for (const auto& s : stages) md << " t " << s << " (s) |";
  md << " t total (s) |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|";
  for (std::size_t i = 0; i < stages.size(); ++i) md << "---|";
  md << "---|\n";
  for (const auto& k : order) {
    const Summary s = summarize(groups[k]);
    std::string reasons;
    for (const auto& [reason, n] : s.failures_by_reason) {
      if (!reasons.empty()) reasons += ", ";
      reasons += toString(reason) + " " + std::to_string(n);
    }
    if (reasons.empty()) reasons = "–";
    md << "| " << k.first << " | " << k.second << " | " << s.count << " | " << cell(s.failureRate(), 1) << " | "
       << cell(s.chamfer, 2) << " | " << cell(s.chamfer_pred_to_gt, 2) << " / " << cell(s.chamfer_gt_to_pred, 2)
       << " | " << seenHidden(s) << " | " << cell(s.hausdorff, 2) << " | " << cell(s.normal_consistency, 3) << " | "
       << ncHalves(s) << " | " << cell(s.nc_prim, 3) << " | " << cell(s.unmatched_predicted, 1) << " | " << cell(s.closed_chamfer, 2) << " | "
       << cell(s.closed_hausdorff, 2) << " | " << cell(s.volume_ratio_median, 3) << " | "
       << (s.failures < s.count ? cell(s.faces, 1) : "–") << " | "
       << (s.failures < s.count ? cell(s.vertices, 1) : "–") << " | " << reasons << " |";
    for (const auto& stage : stages) {
      auto it = s.mean_seconds.find(stage);
      md << " " << (it == s.mean_seconds.end() ? std::string("–") : cell(it->second, 3)) << " |";
    }
    auto total = s.mean_seconds.find("total");
    md << " " << (total == s.mean_seconds.end() ? std::string("–") : cell(total->second, 3)) << " |\n";
  }
  return md.str();
}

// Median and 90th percentile of each stage per (method, assembler), over every level.
std::string latencyTable(const std::vector<EvaluationRecord>& records) {
  // Nothing runs for sanity rows, and the metrics' own time is not the method's latency.
  Rows rows = groupRows(records, /*with_sanity=*/false, "evaluate");
  const auto& order = rows.order;
  auto& groups = rows.groups;
  const auto& stages = rows.stages;
  if (order.empty()) return "";
  std::ostringstream md;
  md << "## Latency (wall seconds per case: median / 90th percentile, all levels)\n\n| Method | Assembler | N |";
  for (const auto& s : stages) md << " " << s << " |";
  md << "\n|---|---|---|";
  for (std::size_t i = 0; i < stages.size(); ++i) md << "---|";
  md << "\n";
  for (const auto& k : order) {
    const Summary s = summarize(groups[k]);
    md << "| " << k.first << " | " << k.second << " | " << s.count << " |";
    for (const auto& stage : stages) {
      const auto m = s.median_seconds.find(stage);
      md << " " << (m == s.median_seconds.end() ? std::string("–") : cell(m->second, 3) + " / " + cell(s.p90_seconds.at(stage), 3))
         << " |";
    }
    md << "\n";
  }
  return md.str() + "\n";
}

}  // namespace

std::string toString(FailureReason reason) {
  for (const auto& [r, name] : reasonNames())
    if (r == reason) return name;
  return "unknown";
}

FailureReason failureReasonFromString(const std::string& name) {
  for (const auto& [r, n] : reasonNames())
    if (name == n) return r;
  throw InvalidInputError("unknown failure reason '" + name + "'");
}

FailureReason classifyMesh(const SurfaceMesh& mesh) {
  if (mesh.faces.empty() || mesh.vertices.empty()) return FailureReason::EmptyMesh;
  try {
    mesh.validate();
    if (!(surfaceArea(mesh) > 0.0)) return FailureReason::EmptyMesh;
  } catch (const Error&) {
    return FailureReason::EmptyMesh;
  }
  const MeshTopology t = analyseTopology(mesh);
  if (!t.isManifold()) return FailureReason::NotManifold;
  if (!t.isClosed()) return FailureReason::NotClosed;
  if (!t.isOriented()) return FailureReason::NotOriented;
  return FailureReason::None;
}

std::string EvaluationRecord::key() const {
  return method + "|" + assembler + "|" + part + "|" + std::to_string(level) + "|" + std::to_string(view);
}

void EvaluationRecord::setScores(const MeshMetrics& metrics) {
  chamfer = metrics.chamfer;
  chamfer_pred_to_gt = metrics.chamfer_pred_to_gt;
  chamfer_gt_to_pred = metrics.chamfer_gt_to_pred;
  hidden_fraction = metrics.hidden_fraction;
  chamfer_gt_to_pred_seen = metrics.chamfer_gt_to_pred_seen;
  chamfer_gt_to_pred_hidden = metrics.chamfer_gt_to_pred_hidden;
  hausdorff = metrics.hausdorff;
  normal_consistency = metrics.normal_consistency;
  nc_pred_to_gt = metrics.normal_consistency_pred_to_gt;
  nc_gt_to_pred = metrics.normal_consistency_gt_to_pred;
  nc_gt_to_pred_seen = metrics.normal_consistency_gt_to_pred_seen;
  nc_gt_to_pred_hidden = metrics.normal_consistency_gt_to_pred_hidden;
}

const std::vector<std::string>& stageNames() {
  static const std::vector<std::string> names = {"segment",  "complete", "fuse",     "prior", "reconstruct",
                                                 "simplify", "assemble", "evaluate", "total"};
  return names;
}

std::string csvHeader() {
  std::string h;
  for (std::size_t i = 0; i < kNumFixed; ++i) h += (i ? "," : "") + std::string(kFixedColumns[i]);
  for (const auto& s : stageNames()) h += ",t_" + s;
  return h + ",message";
}

void appendRecord(std::ostream& out, const EvaluationRecord& r) {
  out << quote(r.method) << ',' << quote(r.assembler) << ',' << quote(r.part) << ',' << r.level << ',' << r.view << ','
      << (r.failed() ? "failed" : "ok") << ',' << toString(r.reason) << ',' << formatNumber(r.chamfer, 9) << ','
      << formatNumber(r.hausdorff, 9) << ',' << formatNumber(r.normal_consistency, 9) << ','
      << (r.nc_prim < 0 ? std::string() : formatNumber(r.nc_prim, 9)) << ','
      << (r.unmatched_predicted < 0 ? std::string() : std::to_string(r.unmatched_predicted)) << ',' << r.num_faces
      << ',' << r.num_vertices << ',' << (r.failed() ? 0 : 1) << ',' << formatNumber(r.volume_ratio, 9) << ','
      << formatNumber(r.chamfer_pred_to_gt, 9) << ',' << formatNumber(r.chamfer_gt_to_pred, 9) << ','
      << formatNumber(r.hidden_fraction, 9) << ',' << formatNumber(r.chamfer_gt_to_pred_seen, 9) << ','
      << formatNumber(r.chamfer_gt_to_pred_hidden, 9) << ',' << formatNumber(r.nc_pred_to_gt, 9) << ','
      << formatNumber(r.nc_gt_to_pred, 9) << ',' << formatNumber(r.nc_gt_to_pred_seen, 9) << ','
      << formatNumber(r.nc_gt_to_pred_hidden, 9);
  for (const auto& s : stageNames()) {
    auto it = r.seconds.find(s);
    out << ',' << (it == r.seconds.end() ? std::string() : formatNumber(it->second, 6));
  }
  out << ',' << quote(r.message) << '\n';
}

std::vector<EvaluationRecord> readRecords(const std::string& path, std::size_t* skipped_lines) {
  std::vector<EvaluationRecord> records;
  if (skipped_lines) *skipped_lines = 0;
  std::ifstream in(path, std::ios::binary);
  if (!in) return records;
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (text.empty()) return records;
  std::istringstream lines(text);
  std::string line;
  std::getline(lines, line);
  if (!line.empty() && line.back() == '\r') line.pop_back();
  if (line != csvHeader())
    throw IoError("'" + path + "' is not a paco_eval CSV of this version (its header differs); "
                  "choose another output folder or delete the file to start over");
  const bool ends_with_newline = text.back() == '\n';
  std::vector<std::string> f;
  const std::size_t expected = kNumFixed + stageNames().size() + 1;
  while (std::getline(lines, line)) {
    // A last line without its newline was cut by an interruption.
    if (lines.eof() && !ends_with_newline) {
      if (skipped_lines) ++*skipped_lines;
      break;
    }
    if (line.empty()) continue;
    if (!splitCsv(line, f) || f.size() != expected) {
      if (skipped_lines) ++*skipped_lines;
      continue;
    }
    try {
      EvaluationRecord r;
      r.method = f[0];
      r.assembler = f[1];
      r.part = f[2];
      r.level = std::stoi(f[3]);
      r.view = std::stoi(f[4]);
      r.reason = failureReasonFromString(f[6]);
      r.chamfer = parseFiniteNumber(f[7]);
      r.hausdorff = parseFiniteNumber(f[8]);
      r.normal_consistency = parseFiniteNumber(f[9]);
      r.nc_prim = f[10].empty() ? -1.0 : parseFiniteNumber(f[10]);
      r.unmatched_predicted = f[11].empty() ? -1 : std::stoi(f[11]);
      r.num_faces = static_cast<std::size_t>(std::stoull(f[12]));
      r.num_vertices = static_cast<std::size_t>(std::stoull(f[13]));
      r.volume_ratio = parseNumber(f[15]);
      r.chamfer_pred_to_gt = parseNumber(f[16]);
      r.chamfer_gt_to_pred = parseNumber(f[17]);
      r.hidden_fraction = parseNumber(f[18]);
      r.chamfer_gt_to_pred_seen = parseNumber(f[19]);
      r.chamfer_gt_to_pred_hidden = parseNumber(f[20]);
      r.nc_pred_to_gt = parseNumber(f[21]);
      r.nc_gt_to_pred = parseNumber(f[22]);
      r.nc_gt_to_pred_seen = parseNumber(f[23]);
      r.nc_gt_to_pred_hidden = parseNumber(f[24]);
      for (std::size_t i = 0; i < stageNames().size(); ++i)
        if (!f[kNumFixed + i].empty()) r.seconds[stageNames()[i]] = parseNumber(f[kNumFixed + i]);
      r.message = f.back();
      records.push_back(std::move(r));
    } catch (const std::exception&) {
      if (skipped_lines) ++*skipped_lines;
    }
  }
  return records;
}

Summary summarize(const std::vector<EvaluationRecord>& records) {
  Summary s;
  s.count = records.size();
  std::vector<double> cd, cd_pred_to_gt, cd_gt_to_pred, hd, nc, prim, unmatched, ccd, chd, faces, vertices, volume;
  std::vector<double> hidden, gt_to_pred_seen, gt_to_pred_hidden, nc_pred_to_gt, nc_gt_to_pred, nc_seen, nc_hidden;
  std::map<std::string, std::vector<double>> times;
  for (const auto& r : records) {
    cd.push_back(r.chamfer);
    cd_pred_to_gt.push_back(r.chamfer_pred_to_gt);
    cd_gt_to_pred.push_back(r.chamfer_gt_to_pred);
    if (!std::isnan(r.hidden_fraction)) hidden.push_back(r.hidden_fraction);
    if (!std::isnan(r.chamfer_gt_to_pred_seen)) gt_to_pred_seen.push_back(r.chamfer_gt_to_pred_seen);
    if (!std::isnan(r.chamfer_gt_to_pred_hidden)) gt_to_pred_hidden.push_back(r.chamfer_gt_to_pred_hidden);
    hd.push_back(r.hausdorff);
    nc.push_back(r.normal_consistency);
    if (!std::isnan(r.nc_pred_to_gt)) nc_pred_to_gt.push_back(r.nc_pred_to_gt);
    if (!std::isnan(r.nc_gt_to_pred)) nc_gt_to_pred.push_back(r.nc_gt_to_pred);
    if (!std::isnan(r.nc_gt_to_pred_seen)) nc_seen.push_back(r.nc_gt_to_pred_seen);
    if (!std::isnan(r.nc_gt_to_pred_hidden)) nc_hidden.push_back(r.nc_gt_to_pred_hidden);
    if (r.nc_prim >= 0) prim.push_back(r.nc_prim);
    if (r.unmatched_predicted >= 0) unmatched.push_back(r.unmatched_predicted);
    for (const auto& [stage, t] : r.seconds) times[stage].push_back(t);
    if (r.failed()) {
      ++s.failures;
      ++s.failures_by_reason[r.reason];
    } else {
      ccd.push_back(r.chamfer);
      chd.push_back(r.hausdorff);
      faces.push_back(static_cast<double>(r.num_faces));
      vertices.push_back(static_cast<double>(r.num_vertices));
      if (!std::isnan(r.volume_ratio)) volume.push_back(r.volume_ratio);
    }
  }
  const auto orMinus = [](double v) { return std::isnan(v) ? -1.0 : v; };
  s.chamfer = orMinus(mean(cd));
  s.chamfer_pred_to_gt = orMinus(mean(cd_pred_to_gt));
  s.chamfer_gt_to_pred = orMinus(mean(cd_gt_to_pred));
  s.hidden_fraction = orMinus(mean(hidden));
  s.chamfer_gt_to_pred_seen = orMinus(mean(gt_to_pred_seen));
  s.chamfer_gt_to_pred_hidden = orMinus(mean(gt_to_pred_hidden));
  s.hausdorff = orMinus(mean(hd));
  s.normal_consistency = orMinus(mean(nc));
  s.nc_pred_to_gt = orMinus(mean(nc_pred_to_gt));
  s.nc_gt_to_pred = orMinus(mean(nc_gt_to_pred));
  s.nc_gt_to_pred_seen = orMinus(mean(nc_seen));
  s.nc_gt_to_pred_hidden = orMinus(mean(nc_hidden));
  s.nc_prim = orMinus(mean(prim));
  s.unmatched_predicted = orMinus(mean(unmatched));
  s.closed_chamfer = orMinus(mean(ccd));
  s.closed_hausdorff = orMinus(mean(chd));
  s.faces = faces.empty() ? 0.0 : mean(faces);
  s.vertices = vertices.empty() ? 0.0 : mean(vertices);
  s.volume_ratio_median = median(volume);
  for (const auto& [stage, v] : times) {
    s.mean_seconds[stage] = mean(v);
    s.median_seconds[stage] = median(v);
    s.p90_seconds[stage] = percentile(v, 0.9);
  }
  return s;
}

std::string markdownReport(const std::vector<EvaluationRecord>& records, const std::string& title,
                           const std::string& notes) {
  std::ostringstream md;
  md << "# " << title << "\n\n";
  if (!notes.empty()) md << notes << (notes.back() == '\n' ? "\n" : "\n\n");
  md << "CD and HD are x 100 in the GT's normalised frame (unit bounding-box diagonal); a failed case is "
        "scored as the GT's normalised bounding box. FR is the failure rate in %. \"CD/HD closed\" average "
        "the succeeded cases only. Times are mean wall seconds per case.\n\n";
  std::map<int, std::vector<EvaluationRecord>> by_level;
  for (const auto& r : records) by_level[r.level].push_back(r);
  for (const auto& [level, rs] : by_level) md << "## " << levelName(level) << "\n\n" << table(rs) << "\n";
  if (by_level.size() > 1 || by_level.empty()) md << "## Overall\n\n" << table(records) << "\n";
  md << latencyTable(records);
  return md.str();
}

namespace {

// Accumulates (before, after) pairs of one metric.
struct PairAccumulator {
  std::vector<double> before, after;
  void add(double b, double a) {
    before.push_back(b);
    after.push_back(a);
  }
  PairedDifference result() const {
    PairedDifference d;
    d.count = before.size();
    if (d.count == 0) return d;
    const double n = static_cast<double>(d.count);
    double sum_diff = 0.0;
    for (std::size_t i = 0; i < d.count; ++i) {
      d.before += before[i] / n;
      d.after += after[i] / n;
      sum_diff += after[i] - before[i];
      if (after[i] != before[i]) ++d.changed;
    }
    d.difference = sum_diff / n;
    if (d.count > 1) {
      double squares = 0.0;
      for (std::size_t i = 0; i < d.count; ++i) {
        const double e = after[i] - before[i] - d.difference;
        squares += e * e;
      }
      d.standard_error = std::sqrt(squares / (n - 1.0) / n);
    }
    return d;
  }
};

struct ComparisonAccumulator {
  PairedComparison counts;  // the case counts as they come; the differences are filled in by result()
  PairAccumulator chamfer, hausdorff, normal_consistency, nc_prim;
  void add(const EvaluationRecord& b, const EvaluationRecord& a) {
    counts.failed_before += b.failed() ? 1 : 0;
    counts.failed_after += a.failed() ? 1 : 0;
    chamfer.add(b.chamfer, a.chamfer);
    hausdorff.add(b.hausdorff, a.hausdorff);
    normal_consistency.add(b.normal_consistency, a.normal_consistency);
    if (b.nc_prim >= 0.0 && a.nc_prim >= 0.0) nc_prim.add(b.nc_prim, a.nc_prim);
  }
  bool empty() const { return chamfer.before.empty(); }
  PairedComparison result(const std::string& method, const std::string& assembler, int level) const {
    PairedComparison c = counts;
    c.method = method;
    c.assembler = assembler;
    c.level = level;
    c.chamfer = chamfer.result();
    c.hausdorff = hausdorff.result();
    c.normal_consistency = normal_consistency.result();
    c.nc_prim = nc_prim.result();
    return c;
  }
};

std::string formatPaired(const PairedDifference& d, int decimals) {
  if (d.count == 0) return "";
  char buffer[160];
  std::snprintf(buffer, sizeof(buffer), "%.*f -> %.*f (%+.*f ± %.*f)", decimals, d.before, decimals, d.after,
                decimals, d.difference, decimals, d.standard_error);
  return buffer;
}

}  // namespace

std::vector<PairedComparison> comparePaired(const std::vector<EvaluationRecord>& before,
                                            const std::vector<EvaluationRecord>& after) {
  // Method + assembler in order of first appearance in `before`.
  std::vector<std::pair<std::string, std::string>> groups;
  std::map<std::string, const EvaluationRecord*> after_by_key;
  for (const auto& r : after) after_by_key.emplace(r.key(), &r);  // a key twice: the first counts, as in `before`
  std::set<std::string> before_keys;
  std::map<std::pair<std::string, std::string>, std::map<int, ComparisonAccumulator>> accumulators;
  for (const auto& b : before) {
    if (!before_keys.insert(b.key()).second) continue;
    const std::pair<std::string, std::string> group{b.method, b.assembler};
    if (!accumulators.count(group)) groups.push_back(group);
    auto& by_level = accumulators[group];
    const auto it = after_by_key.find(b.key());
    if (it == after_by_key.end()) {
      ++by_level[b.level].counts.only_before;
      ++by_level[-1].counts.only_before;
      continue;
    }
    by_level[b.level].add(b, *it->second);
    by_level[-1].add(b, *it->second);
  }
  for (const auto& [key, a] : after_by_key) {
    if (before_keys.count(key)) continue;
    const std::pair<std::string, std::string> group{a->method, a->assembler};
    if (!accumulators.count(group)) continue;  // a method or assembler only the second run has
    ++accumulators[group][a->level].counts.only_after;
    ++accumulators[group][-1].counts.only_after;
  }
  std::vector<PairedComparison> comparisons;
  for (const auto& group : groups) {
    const auto& by_level = accumulators[group];
    std::size_t levels = 0;  // with a case in common
    for (const auto& [level, acc] : by_level) {
      if (level < 0 || acc.empty()) continue;
      comparisons.push_back(acc.result(group.first, group.second, level));
      ++levels;
    }
    if (levels > 1) comparisons.push_back(by_level.at(-1).result(group.first, group.second, -1));
  }
  return comparisons;
}

std::string markdownComparison(const std::vector<PairedComparison>& comparisons, const std::string& before_name,
                               const std::string& after_name) {
  std::ostringstream md;
  md << "# " << before_name << " -> " << after_name << "\n\n"
     << "Case by case over the cases both runs have: each metric's mean before -> after, then the mean of "
        "the differences (after - before) ± its standard error. A failed case takes part with its failure-box "
        "scores, as in the report's means. Lower CD and HD, higher NC and NC_prim are better.\n\n"
     << "| method | assembler | level | cases | failed | CD | HD | NC | NC_prim | CD changed |\n"
     << "|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& c : comparisons) {
    md << "| " << c.method << " | " << c.assembler << " | " << (c.level < 0 ? std::string("all") : std::to_string(c.level))
       << " | " << c.chamfer.count;
    if (c.only_before || c.only_after) md << " (" << c.only_before << " only before, " << c.only_after << " only after)";
    md << " | " << c.failed_before << " -> " << c.failed_after << " | " << formatPaired(c.chamfer, 3) << " | "
       << formatPaired(c.hausdorff, 2) << " | " << formatPaired(c.normal_consistency, 4) << " | "
       << formatPaired(c.nc_prim, 4) << " | " << c.chamfer.changed << " |\n";
  }
  if (comparisons.empty()) md << "\nThe two runs have no case in common.\n";
  return md.str();
}

}  // namespace paco::evaluation
