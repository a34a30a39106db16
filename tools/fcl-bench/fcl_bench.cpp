// Peer benchmark: FCL 0.7 on the real jaw pair along a motion, per frame.
//
//   fcl_bench MESH_A MESH_B MOTION.csv [PASSES]
//
// Env: FCL_BENCH_FRAMES=N (first N frames), FCL_BENCH_STRIDE=K (every K-th
// frame, applied before FRAMES), FCL_BENCH_CSV=path (per-frame times).
//
// Meshes: binary or ASCII STL, optionally gzip-compressed (zlib reads plain
// files transparently). Motion: CSV with header t,tx,ty,tz,qw,qx,qy,qz
// ('#' lines are comments, may be .gz), each row the pose of B in A's frame:
// x_A = R(q) * x_B + t. A stays at the identity.
//
// Only the FCL calls are timed (std::chrono::steady_clock around each call).

#include <fcl/fcl.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

using Clock = std::chrono::steady_clock;
using Model = fcl::BVHModel<fcl::OBBRSSd>;

static double secs_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// ---------------------------------------------------------------- input ----

static std::string read_all(const std::string& path) {
  gzFile f = gzopen(path.c_str(), "rb");
  if (!f) throw std::runtime_error("cannot open " + path);
  gzbuffer(f, 1 << 20);
  std::string out;
  std::vector<char> buf(1 << 20);
  for (;;) {
    int n = gzread(f, buf.data(), (unsigned)buf.size());
    if (n < 0) {
      int err = 0;
      std::string msg = gzerror(f, &err);
      gzclose(f);
      throw std::runtime_error("read error in " + path + ": " + msg);
    }
    if (n == 0) break;
    out.append(buf.data(), (size_t)n);
  }
  gzclose(f);
  return out;
}

struct Mesh {
  std::vector<fcl::Vector3d> verts;
  std::vector<fcl::Triangle> tris;
  size_t raw_tris = 0;       // triangles in the file
  size_t degenerate = 0;     // dropped: two corners merged into one vertex
};

struct KeyHash {
  size_t operator()(const std::array<uint32_t, 3>& k) const {
    uint64_t h = 1469598103934665603ull;
    for (uint32_t v : k) { h ^= v; h *= 1099511628211ull; h ^= h >> 29; }
    return (size_t)h;
  }
};

// Merges corners with bit-identical float coordinates (STL stores every
// triangle's corners separately).
class MeshBuilder {
 public:
  explicit MeshBuilder(size_t ntri) { map_.reserve(ntri); m_.tris.reserve(ntri); m_.verts.reserve(ntri / 2 + 16); }
  void add(const float c[9]) {
    size_t id[3];
    for (int i = 0; i < 3; ++i) {
      std::array<uint32_t, 3> k;
      std::memcpy(k.data(), c + 3 * i, 12);
      for (auto& x : k) if (x == 0x80000000u) x = 0;  // -0.0 == 0.0
      auto it = map_.find(k);
      if (it == map_.end()) {
        id[i] = m_.verts.size();
        map_.emplace(k, id[i]);
        m_.verts.emplace_back(c[3 * i], c[3 * i + 1], c[3 * i + 2]);
      } else {
        id[i] = it->second;
      }
    }
    ++m_.raw_tris;
    if (id[0] == id[1] || id[1] == id[2] || id[0] == id[2]) { ++m_.degenerate; return; }
    m_.tris.emplace_back(id[0], id[1], id[2]);
  }
  Mesh take() { return std::move(m_); }

 private:
  Mesh m_;
  std::unordered_map<std::array<uint32_t, 3>, size_t, KeyHash> map_;
};

static Mesh load_stl(const std::string& path) {
  std::string d = read_all(path);
  bool binary = false;
  uint32_t n = 0;
  if (d.size() >= 84) {
    std::memcpy(&n, d.data() + 80, 4);
    binary = (84 + (uint64_t)n * 50 == d.size());
  }
  if (!binary && d.size() >= 84 && d.compare(0, 5, "solid") != 0) binary = true;  // tolerate trailing bytes
  if (binary) {
    if (84 + (uint64_t)n * 50 > d.size()) throw std::runtime_error(path + ": truncated binary STL");
    MeshBuilder b(n);
    float c[9];
    for (uint32_t i = 0; i < n; ++i) {
      std::memcpy(c, d.data() + 84 + (size_t)i * 50 + 12, 36);
      b.add(c);
    }
    return b.take();
  }
  // ASCII: every "vertex x y z", three per facet.
  MeshBuilder b(d.size() / 200);
  std::istringstream in(d);
  std::string tok;
  float c[9];
  int k = 0;
  while (in >> tok) {
    if (tok == "vertex") {
      in >> c[3 * k] >> c[3 * k + 1] >> c[3 * k + 2];
      if (!in) throw std::runtime_error(path + ": bad ASCII STL vertex");
      if (++k == 3) { b.add(c); k = 0; }
    }
  }
  Mesh m = b.take();
  if (m.raw_tris == 0) throw std::runtime_error(path + ": no triangles");
  return m;
}

struct Pose { double t; fcl::Transform3d tf; };

static std::vector<Pose> load_motion(const std::string& path) {
  std::string d = read_all(path);
  std::istringstream in(d);
  std::string line;
  std::vector<std::string> header;
  std::vector<Pose> out;
  int col[8];
  static const char* names[8] = {"t", "tx", "ty", "tz", "qw", "qx", "qy", "qz"};
  size_t lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    size_t s = line.find_first_not_of(" \t");
    if (s == std::string::npos || line[s] == '#') continue;
    std::vector<std::string> f;
    std::stringstream ls(line);
    std::string cell;
    while (std::getline(ls, cell, ',')) {
      size_t a = cell.find_first_not_of(" \t"), b = cell.find_last_not_of(" \t");
      f.push_back(a == std::string::npos ? "" : cell.substr(a, b - a + 1));
    }
    if (header.empty()) {
      header = f;
      for (int i = 0; i < 8; ++i) {
        auto it = std::find(header.begin(), header.end(), names[i]);
        if (it == header.end()) throw std::runtime_error(path + ": header lacks column " + names[i]);
        col[i] = (int)(it - header.begin());
      }
      continue;
    }
    double v[8];
    for (int i = 0; i < 8; ++i) {
      if ((size_t)col[i] >= f.size()) throw std::runtime_error(path + ": short row at line " + std::to_string(lineno));
      v[i] = std::strtod(f[col[i]].c_str(), nullptr);
    }
    Eigen::Quaterniond q(v[4], v[5], v[6], v[7]);  // (w, x, y, z)
    q.normalize();
    fcl::Transform3d tf = fcl::Transform3d::Identity();
    tf.linear() = q.toRotationMatrix();
    tf.translation() = fcl::Vector3d(v[1], v[2], v[3]);
    out.push_back({v[0], tf});
  }
  return out;
}

static long env_long(const char* name, long dflt) {
  const char* s = std::getenv(name);
  if (!s || !*s) return dflt;
  return std::strtol(s, nullptr, 10);
}

// ---------------------------------------------------------------- stats ----

static double pct(std::vector<double> v, double p) {  // nearest rank
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  size_t k = (size_t)std::ceil(p * v.size());
  if (k < 1) k = 1;
  return v[std::min(k, v.size()) - 1];
}

// ----------------------------------------------------------------- main ----

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: %s MESH_A MESH_B MOTION.csv [PASSES]\n", argv[0]);
    return 2;
  }
  const std::string pathA = argv[1], pathB = argv[2], pathM = argv[3];
  const int passes = argc > 4 ? std::max(1, std::atoi(argv[4])) : 3;
  try {
    // ---- meshes and BVH builds
    auto t0 = Clock::now();
    Mesh A = load_stl(pathA);
    double loadA = secs_since(t0);
    t0 = Clock::now();
    Mesh B = load_stl(pathB);
    double loadB = secs_since(t0);

    auto build = [](const Mesh& m, double& secs) {
      auto model = std::make_shared<Model>();
      auto t = Clock::now();
      model->beginModel((int)m.tris.size(), (int)m.verts.size());
      model->addSubModel(m.verts, m.tris);
      model->endModel();
      secs = secs_since(t);
      return model;
    };
    double buildA = 0, buildB = 0;
    auto modelA = build(A, buildA);
    auto modelB = build(B, buildB);

    // ---- motion
    std::vector<Pose> all = load_motion(pathM);
    const long stride = std::max(1L, env_long("FCL_BENCH_STRIDE", 1));
    const long maxf = env_long("FCL_BENCH_FRAMES", 0);
    std::vector<size_t> idx;
    for (size_t i = 0; i < all.size(); i += (size_t)stride) {
      if (maxf > 0 && (long)idx.size() >= maxf) break;
      idx.push_back(i);
    }
    if (idx.empty()) throw std::runtime_error("no frames selected");

    std::printf("# FCL peer benchmark\n\n");
    std::printf("- FCL %s, BVHModel<OBBRSSd>, g++ -O2, steady_clock around each FCL call only\n", FCL_VERSION);
    std::printf("- A: %s — %zu triangles in file, %zu vertices after merging, %zu degenerate dropped\n",
                pathA.c_str(), A.raw_tris, A.verts.size(), A.degenerate);
    std::printf("- B: %s — %zu triangles in file, %zu vertices after merging, %zu degenerate dropped\n",
                pathB.c_str(), B.raw_tris, B.verts.size(), B.degenerate);
    std::printf("- load+parse: A %.2f s, B %.2f s; BVH build (beginModel..endModel): A %.3f s, B %.3f s\n",
                loadA, loadB, buildA, buildB);
    std::printf("- motion: %s — %zu rows; using %zu frames (stride %ld%s), %d passes (best-of-%d per frame)\n\n",
                pathM.c_str(), all.size(), idx.size(), stride,
                maxf > 0 ? (", first " + std::to_string(maxf)).c_str() : "", passes, passes);
    std::fflush(stdout);

    fcl::CollisionObjectd objA(modelA, fcl::Transform3d::Identity());
    fcl::CollisionObjectd objB(modelB, fcl::Transform3d::Identity());

    fcl::DistanceRequestd dreq;
    dreq.enable_nearest_points = true;  // rel_err = abs_err = 0 by default
    fcl::CollisionRequestd creq_first(1, false);
    fcl::CollisionRequestd creq_all(100000, true);

    const int NQ = 3;
    const char* qname[NQ] = {"FCL exact distance", "FCL first contact (boolean)", "FCL all contacts"};
    const size_t nf = idx.size();
    std::vector<double> ns_first[NQ], ns_best[NQ];
    std::vector<double> result[NQ];
    for (int q = 0; q < NQ; ++q) {
      ns_first[q].assign(nf, 0);
      ns_best[q].assign(nf, INFINITY);
      result[q].assign(nf, 0);
    }
    std::vector<double> np_gap(nf, 0);  // | |p0-p1| - distance |, nearest points check
    std::vector<bool> mismatch(nf, false);

    auto ns = [](Clock::time_point a, Clock::time_point b) {
      return (double)std::chrono::duration_cast<std::chrono::nanoseconds>(b - a).count();
    };

    auto wall0 = Clock::now();
    for (int p = 0; p < passes; ++p) {
      for (size_t f = 0; f < nf; ++f) {
        objB.setTransform(all[idx[f]].tf);
        objB.computeAABB();
        double r[NQ], t[NQ];
        {
          fcl::DistanceResultd dres;
          auto a = Clock::now();
          fcl::distance(&objA, &objB, dreq, dres);
          auto b = Clock::now();
          t[0] = ns(a, b);
          r[0] = dres.min_distance;
          if (p == 0) np_gap[f] = std::fabs((dres.nearest_points[0] - dres.nearest_points[1]).norm() - dres.min_distance);
        }
        {
          fcl::CollisionResultd cres;
          auto a = Clock::now();
          fcl::collide(&objA, &objB, creq_first, cres);
          auto b = Clock::now();
          t[1] = ns(a, b);
          r[1] = cres.isCollision() ? 1 : 0;
        }
        {
          fcl::CollisionResultd cres;
          auto a = Clock::now();
          fcl::collide(&objA, &objB, creq_all, cres);
          auto b = Clock::now();
          t[2] = ns(a, b);
          r[2] = (double)cres.numContacts();
        }
        for (int q = 0; q < NQ; ++q) {
          if (p == 0) { ns_first[q][f] = t[q]; result[q][f] = r[q]; }
          else if (r[q] != result[q][f]) mismatch[f] = true;  // must be deterministic
          ns_best[q][f] = std::min(ns_best[q][f], t[q]);
        }
      }
      std::fprintf(stderr, "pass %d/%d done (%.1f s)\n", p + 1, passes, secs_since(wall0));
    }

    // ---- tables
    std::printf("| query | frames | best p50 µs | best p99 µs | best max µs | 1st p50 µs | 1st p99 µs | 1st max µs | counts |\n");
    std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---|\n");
    size_t coll_frames = 0, zero_dist = 0, neg_dist = 0, disagree = 0, capped = 0;
    std::vector<double> contacts_in_coll, dist_apart;
    for (size_t f = 0; f < nf; ++f) {
      bool c = result[1][f] != 0;
      coll_frames += c;
      if (result[0][f] == 0) ++zero_dist;
      if (result[0][f] < 0) ++neg_dist;
      if (result[0][f] > 0) dist_apart.push_back(result[0][f]);
      if (c != (result[0][f] <= 0) || c != (result[2][f] > 0)) ++disagree;
      if (c) contacts_in_coll.push_back(result[2][f]);
      if (result[2][f] >= 100000) ++capped;
    }
    std::vector<double> all_contacts(result[2]);
    for (int q = 0; q < NQ; ++q) {
      auto us = [](std::vector<double> v) { for (auto& x : v) x /= 1000.0; return v; };
      std::vector<double> b = us(ns_best[q]), f1 = us(ns_first[q]);
      char counts[256];
      if (q == 0)
        std::snprintf(counts, sizeof counts, "distance == 0: %zu, < 0: %zu; apart: min %.3f / p50 %.3f / max %.3f mm",
                      zero_dist, neg_dist, dist_apart.empty() ? NAN : *std::min_element(dist_apart.begin(), dist_apart.end()),
                      pct(dist_apart, 0.5), dist_apart.empty() ? NAN : *std::max_element(dist_apart.begin(), dist_apart.end()));
      else if (q == 1)
        std::snprintf(counts, sizeof counts, "in collision: %zu of %zu", coll_frames, nf);
      else
        std::snprintf(counts, sizeof counts, "in collision: %zu; contacts median %.0f (all frames) / %.0f (colliding frames), max %.0f",
                      (size_t)std::count_if(all_contacts.begin(), all_contacts.end(), [](double x) { return x > 0; }),
                      pct(all_contacts, 0.5), pct(contacts_in_coll, 0.5),
                      *std::max_element(all_contacts.begin(), all_contacts.end()));
      std::printf("| %s | %zu | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %s |\n", qname[q], nf,
                  pct(b, 0.5), pct(b, 0.99), *std::max_element(b.begin(), b.end()),
                  pct(f1, 0.5), pct(f1, 0.99), *std::max_element(f1.begin(), f1.end()), counts);
    }
    double gap_apart = 0, gap_coll = 0;  // nearest points: world frame, |p0-p1| should equal distance
    for (size_t f = 0; f < nf; ++f)
      (result[0][f] > 0 ? gap_apart : gap_coll) = std::max(result[0][f] > 0 ? gap_apart : gap_coll, np_gap[f]);
    size_t nondet = (size_t)std::count(mismatch.begin(), mismatch.end(), true);
    std::printf("\nChecks: frames where distance/boolean/all-contacts disagree on contact: %zu; "
                "nearest points max | |p0-p1| - distance |: %.3g mm apart, %.3g mm in contact (FCL's points are then only "
                "from one intersecting triangle pair, not a witness); frames whose results changed between passes: %zu; "
                "frames at the 100000-contact cap: %zu\n",
                disagree, gap_apart, gap_coll, nondet, capped);
    std::printf("Timing wall (all passes, incl. setTransform): %.1f s\n", secs_since(wall0));

    if (const char* csv = std::getenv("FCL_BENCH_CSV")) {
      if (*csv) {
        std::ofstream o(csv);
        if (!o) throw std::runtime_error(std::string("cannot write ") + csv);
        o << "frame,query,ns_first,ns_best,result\n";
        static const char* qkey[NQ] = {"distance", "first_contact", "all_contacts"};
        o.precision(17);
        for (size_t f = 0; f < nf; ++f)
          for (int q = 0; q < NQ; ++q)
            o << idx[f] << ',' << qkey[q] << ',' << (long long)ns_first[q][f] << ','
              << (long long)ns_best[q][f] << ',' << result[q][f] << '\n';
        std::fprintf(stderr, "per-frame times written to %s\n", csv);
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fcl_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
