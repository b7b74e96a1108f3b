// Recording files: written step by step, read whole, replayed by a cursor
// that rebuilds each step's pair set from the pairs that left and joined.
#include "rtcd/sim/recording.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <iterator>
#include <sstream>

namespace rtcd::sim {
namespace {

static_assert(std::endian::native == std::endian::little, "recordings are little-endian");

constexpr char kMagic[8] = {'R', 'T', 'C', 'D', 'R', 'E', 'C', '1'};
constexpr uint32_t kStepTag = 0x50455453;  // "STEP"

template <class T>
void put(std::ostream& out, const T& v) {
  out.write(reinterpret_cast<const char*>(&v), sizeof v);
}
template <class T>
void put_all(std::ostream& out, const std::vector<T>& v) {
  put(out, uint32_t(v.size()));
  out.write(reinterpret_cast<const char*>(v.data()), std::streamsize(v.size() * sizeof(T)));
}
void put_text(std::ostream& out, const std::string& s) {
  put(out, uint32_t(s.size()));
  out.write(s.data(), std::streamsize(s.size()));
}

// Reads fields off the bytes; every shortfall names what was being read.
class Reader {
 public:
  Reader(std::string_view bytes, std::string name) : bytes_(bytes), name_(std::move(name)) {}
  bool done() const { return at_ == bytes_.size(); }
  [[noreturn]] void fail(const std::string& what) const {
    throw RecordingError(name_ + ": " + where_ + what);
  }
  void at(std::string where) { where_ = std::move(where); }

  template <class T>
  T get(const char* what) {
    T v;
    take(&v, sizeof v, what);
    return v;
  }
  template <class T>
  void get_all(std::vector<T>& v, const char* what, size_t most) {
    const uint32_t n = get<uint32_t>(what);
    if (n > most) fail(std::string(what) + ": " + std::to_string(n) + " entries, more than the " +
                       std::to_string(most) + " possible");
    v.resize(n);
    take(v.data(), n * sizeof(T), what);
  }
  std::string text(const char* what) {
    const uint32_t n = get<uint32_t>(what);
    std::string s(n > bytes_.size() - at_ ? 0 : n, '\0');
    take(s.data(), n, what);
    return s;
  }

 private:
  void take(void* to, size_t n, const char* what) {
    if (n > bytes_.size() - at_) fail(std::string("truncated in ") + what);
    if (n) std::memcpy(to, bytes_.data() + at_, n);
    at_ += n;
  }
  std::string_view bytes_;
  std::string name_, where_;
  size_t at_ = 0;
};

}  // namespace

Recording Recording::read(const std::string& path, const SceneLimits& limits) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw RecordingError(path + ": cannot open");
  std::ostringstream text;
  text << in.rdbuf();
  return parse(text.str(), path, limits);
}

Recording Recording::parse(std::string_view bytes, const std::string& name, const SceneLimits& limits) {
  Reader r(bytes, name);
  char magic[8];
  for (char& c : magic) c = r.get<char>("the header");
  if (!std::equal(std::begin(magic), std::end(magic), std::begin(kMagic)))
    r.fail("not an rtcd recording (no RTCDREC1 header)");
  Recording rec;
  rec.scene_path_ = r.text("the scene path");
  rec.scene_text_ = r.text("the scene text");
  try {
    rec.scene_ = parse_scene(rec.scene_text_, rec.scene_path_, limits);
  } catch (const SceneError& e) {
    r.fail(std::string("its scene: ") + e.what());
  }
  const uint64_t most_bodies = std::min<uint64_t>(rec.scene_.body_count() + 1, UINT32_MAX);
  uint64_t pair_count = 0;
  while (!r.done()) {
    const uint64_t index = rec.steps_.size();
    r.at("step " + std::to_string(index) + ": ");
    if (r.get<uint32_t>("the step tag") != kStepTag) r.fail("no step tag where a step begins");
    RecordedStep s;
    s.step = r.get<uint64_t>("the step number");
    if (s.step != index) r.fail("numbered " + std::to_string(s.step));
    s.time = r.get<double>("the time");
    s.bodies = r.get<uint32_t>("the body count");
    s.pairs = r.get<uint32_t>("the pair count");
    s.contacts = r.get<uint32_t>("the contact count");
    s.ground_contacts = r.get<uint32_t>("the ground contact count");
    s.kinetic_energy = r.get<double>("the kinetic energy");
    for (double* t : {&s.seconds_broad, &s.seconds_narrow, &s.seconds_solver, &s.seconds_effects, &s.seconds_total})
      *t = r.get<double>("the timings");
    std::vector<uint32_t> kinds;
    r.get_all(kinds, "the new bodies", most_bodies - rec.kinds_.size());
    for (uint32_t k : kinds)
      if (k != Simulation::kGroundKind && k >= rec.scene_.bodies.size())
        r.fail("a body of kind " + std::to_string(k) + ", but the scene has " +
               std::to_string(rec.scene_.bodies.size()) + " entries");
    rec.kinds_.insert(rec.kinds_.end(), kinds.begin(), kinds.end());
    if (s.bodies != rec.kinds_.size())
      r.fail(std::to_string(s.bodies) + " bodies, but " + std::to_string(rec.kinds_.size()) + " have appeared");
    Encoded e;
    r.get_all(e.poses, "the poses", 7 * size_t(s.bodies));
    if (e.poses.size() != 7 * size_t(s.bodies)) r.fail("poses for other than its " + std::to_string(s.bodies) + " bodies");
    for (float v : e.poses)
      if (!std::isfinite(v)) r.fail("a non-finite pose");
    r.get_all(e.left, "the pairs that left", pair_count);
    r.get_all(e.joined, "the pairs that joined", size_t(s.bodies) * s.bodies);
    for (const auto* list : {&e.left, &e.joined}) {
      if (!std::is_sorted(list->begin(), list->end())) r.fail("pairs out of order");
      for (uint64_t k : *list)
        if (const BodyPair p = pair_of_key(k); p.a >= p.b || p.b >= s.bodies)
          r.fail("a pair (" + std::to_string(p.a) + ", " + std::to_string(p.b) + ") of bodies it does not have");
    }
    if (pair_count - e.left.size() + e.joined.size() != s.pairs)
      r.fail(std::to_string(s.pairs) + " pairs, but its changes leave " +
             std::to_string(pair_count - e.left.size() + e.joined.size()));
    pair_count = s.pairs;
    rec.steps_.push_back(s);
    rec.encoded_.push_back(std::move(e));
  }
  return rec;
}

bool Recording::Cursor::next(RecordedFrame& frame) {
  if (next_ >= recording_->steps_.size()) return false;
  const Encoded& e = recording_->encoded_[next_];
  scratch_.clear();
  std::set_difference(keys_.begin(), keys_.end(), e.left.begin(), e.left.end(), std::back_inserter(scratch_));
  if (keys_.size() - scratch_.size() != e.left.size())
    throw RecordingError("step " + std::to_string(next_) + ": a pair left that was not there");
  keys_.clear();
  std::set_union(scratch_.begin(), scratch_.end(), e.joined.begin(), e.joined.end(), std::back_inserter(keys_));
  if (keys_.size() != scratch_.size() + e.joined.size())
    throw RecordingError("step " + std::to_string(next_) + ": a pair joined that was already there");
  frame.pairs.clear();
  for (uint64_t k : keys_) frame.pairs.push_back(pair_of_key(k));
  frame.poses.resize(e.poses.size() / 7);
  for (size_t i = 0; i < frame.poses.size(); ++i) {
    const float* p = &e.poses[7 * i];
    frame.poses[i].position = Eigen::Vector3d(p[0], p[1], p[2]);
    Eigen::Quaterniond q(p[6], p[3], p[4], p[5]);
    frame.poses[i].orientation = q.norm() > 0 ? q.normalized() : Eigen::Quaterniond::Identity();
  }
  ++next_;
  return true;
}

RecordingWriter::RecordingWriter(const std::string& path, const std::string& scene_path, const std::string& scene_text)
    : path_(path), out_(path, std::ios::binary | std::ios::trunc) {
  if (!out_) throw RecordingError(path + ": cannot write");
  out_.write(kMagic, sizeof kMagic);
  put_text(out_, scene_path);
  put_text(out_, scene_text);
}

void RecordingWriter::append(const Simulation& simulation) {
  const StepRecord& s = simulation.last();
  const std::vector<uint32_t> kinds = simulation.body_kinds();
  simulation.shape_poses(poses_);
  keys_.clear();
  for (const BodyPair& p : simulation.last_pairs()) keys_.push_back(pair_key(p.a, p.b));
  std::sort(keys_.begin(), keys_.end());
  keys_.erase(std::unique(keys_.begin(), keys_.end()), keys_.end());
  left_.clear();
  joined_.clear();
  std::set_difference(previous_.begin(), previous_.end(), keys_.begin(), keys_.end(), std::back_inserter(left_));
  std::set_difference(keys_.begin(), keys_.end(), previous_.begin(), previous_.end(), std::back_inserter(joined_));
  previous_.swap(keys_);

  put(out_, kStepTag);
  put(out_, s.step);
  put(out_, s.time);
  put(out_, uint32_t(kinds.size()));
  put(out_, uint32_t(previous_.size()));
  put(out_, uint32_t(s.contacts));
  put(out_, uint32_t(s.ground_contacts));
  put(out_, s.kinetic_energy);
  for (double t : {s.seconds_broad, s.seconds_narrow, s.seconds_solver, s.seconds_effects, s.seconds_total}) put(out_, t);
  put_all(out_, std::vector<uint32_t>(kinds.begin() + std::ptrdiff_t(kinds_written_), kinds.end()));
  kinds_written_ = kinds.size();
  packed_.clear();
  for (const Pose& p : poses_) {
    const Eigen::Quaterniond& q = p.orientation;
    packed_.insert(packed_.end(), {float(p.position.x()), float(p.position.y()), float(p.position.z()), float(q.x()),
                                   float(q.y()), float(q.z()), float(q.w())});
  }
  put_all(out_, packed_);
  put_all(out_, left_);
  put_all(out_, joined_);
  if (!out_) throw RecordingError(path_ + ": write failed at step " + std::to_string(s.step));
}

void RecordingWriter::close() {
  out_.flush();
  if (!out_) throw RecordingError(path_ + ": write failed");
  out_.close();
}

}  // namespace rtcd::sim
