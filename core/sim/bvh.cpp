#include "sim/bvh.hpp"

#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include "common/error.hpp"
#include "sim/option_checks.hpp"

namespace posefuse::sim {
namespace {

constexpr int kMaxJoints = 4096;  // a bound against absurd files; real rigs have < 100

struct Token {
  std::string_view text;
  int line = 0;  // 1-based
};

// The file split into lines (without '\r' or '\n'), each with its 1-based number.
std::vector<std::string_view> split_lines(std::string_view text) {
  std::vector<std::string_view> lines;
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(start, end - start);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    lines.push_back(line);
    start = end + 1;
  }
  return lines;
}

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\f' || c == '\v'; }

void append_tokens(std::string_view line, int line_number, std::vector<Token>& out) {
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_space(line[i])) ++i;
    if (i >= line.size()) break;
    std::size_t j = i;
    while (j < line.size() && !is_space(line[j])) ++j;
    out.push_back({line.substr(i, j - i), line_number});
    i = j;
  }
}

class Parser {
 public:
  Parser(std::string_view text, std::string source) : source_(std::move(source)), lines_(split_lines(text)) {}

  BvhClip parse() {
    BvhClip clip;
    const int motion_line = parse_hierarchy(clip.skeleton);
    parse_motion(motion_line, clip);
    return clip;
  }

 private:
  [[noreturn]] void fail(int line, const std::string& message) const { throw_invalid(where(line), message); }
  [[noreturn]] void truncated(int line, const std::string& message) const {
    throw Error(ErrorCode::kDataLoss, where(line), message + " (file ends early)");
  }
  std::string where(int line) const { return source_ + ":" + std::to_string(line); }

  double number(const Token& t, const char* what) const {
    double value = 0.0;
    const char* first = t.text.data();
    const char* last = first + t.text.size();
    // from_chars does not accept a leading '+'; skip one, but not "+-5".
    if (!t.text.empty() && *first == '+' && t.text.size() > 1 && first[1] != '-') ++first;
    const auto [ptr, ec] = std::from_chars(first, last, value);
    if (ec != std::errc() || ptr != last || !std::isfinite(value)) {
      fail(t.line, std::string(what) + " is not a finite number: '" + std::string(t.text) + "'");
    }
    return value;
  }

  // Tokens of the hierarchy part: everything up to (excluding) the line starting with MOTION.
  // Returns the 0-based index of the MOTION line.
  int parse_hierarchy(BvhSkeleton& skeleton) {
    std::vector<Token> tokens;
    int motion_index = -1;
    for (std::size_t i = 0; i < lines_.size(); ++i) {
      std::vector<Token> line_tokens;
      append_tokens(lines_[i], static_cast<int>(i) + 1, line_tokens);
      if (!line_tokens.empty() && line_tokens[0].text == "MOTION") {
        if (line_tokens.size() != 1) fail(static_cast<int>(i) + 1, "unexpected text after MOTION");
        motion_index = static_cast<int>(i);
        break;
      }
      tokens.insert(tokens.end(), line_tokens.begin(), line_tokens.end());
    }
    tokens_ = std::move(tokens);
    pos_ = 0;
    motion_index_ = motion_index;
    const int last_line = static_cast<int>(lines_.size());

    expect("HIERARCHY", last_line);
    const Token root = next(last_line, "ROOT");
    if (root.text != "ROOT") fail(root.line, "expected ROOT, found '" + std::string(root.text) + "'");
    parse_joint(skeleton, -1, last_line);
    if (pos_ < tokens_.size()) {
      const Token& t = tokens_[pos_];
      fail(t.line, "unexpected '" + std::string(t.text) +
                       "' after the root joint (only one ROOT "
                       "is supported; or unbalanced braces)");
    }
    if (motion_index < 0) fail(last_line, "missing MOTION section");
    return motion_index;
  }

  Token next(int last_line, const char* expected) {
    if (pos_ >= tokens_.size()) {
      if (motion_index_ >= 0) {
        fail(motion_index_ + 1, std::string("MOTION reached where '") + expected +
                                    "' was expected (unbalanced braces or an unfinished joint)");
      }
      truncated(tokens_.empty() ? last_line : tokens_.back().line,
                std::string("hierarchy ends where '") + expected + "' was expected");
    }
    return tokens_[pos_++];
  }

  void expect(std::string_view word, int last_line) {
    const Token t = next(last_line, std::string(word).c_str());
    if (t.text != word) {
      fail(t.line, "expected '" + std::string(word) + "', found '" + std::string(t.text) + "'");
    }
  }

  Vec3 parse_offset(int last_line) {
    expect("OFFSET", last_line);
    Vec3 v;
    for (int k = 0; k < 3; ++k) v[k] = number(next(last_line, "an OFFSET value"), "OFFSET value");
    return v;
  }

  static bool channel_from_name(std::string_view name, BvhChannel& out) {
    static const std::pair<std::string_view, BvhChannel> kNames[] = {
        {"Xposition", BvhChannel::kXposition}, {"Yposition", BvhChannel::kYposition},
        {"Zposition", BvhChannel::kZposition}, {"Xrotation", BvhChannel::kXrotation},
        {"Yrotation", BvhChannel::kYrotation}, {"Zrotation", BvhChannel::kZrotation}};
    for (const auto& [n, c] : kNames) {
      if (n == name) {
        out = c;
        return true;
      }
    }
    return false;
  }

  // At the joint's name (after ROOT / JOINT).
  void parse_joint(BvhSkeleton& skeleton, int parent, int last_line) {
    const Token name = next(last_line, "a joint name");
    if (name.text == "{" || name.text == "}") fail(name.line, "joint without a name");
    if (static_cast<int>(skeleton.joints.size()) >= kMaxJoints) {
      throw Error(ErrorCode::kResourceExhausted, where(name.line),
                  "more than " + std::to_string(kMaxJoints) + " joints");
    }
    const int index = static_cast<int>(skeleton.joints.size());
    skeleton.joints.push_back({});
    skeleton.joints[index].name = std::string(name.text);
    skeleton.joints[index].parent = parent;
    expect("{", last_line);
    skeleton.joints[index].offset = parse_offset(last_line);

    const Token channels_word = next(last_line, "CHANNELS");
    if (channels_word.text != "CHANNELS") {
      fail(channels_word.line, "expected CHANNELS in joint '" + std::string(name.text) + "', found '" +
                                   std::string(channels_word.text) + "'");
    }
    const Token count_token = next(last_line, "the channel count");
    const double count = number(count_token, "channel count");
    if (count < 0 || count > 6 || count != std::floor(count)) {
      fail(count_token.line, "channel count must be an integer 0..6, got '" + std::string(count_token.text) + "'");
    }
    skeleton.joints[index].first_channel = skeleton.channel_count;
    for (int k = 0; k < static_cast<int>(count); ++k) {
      const Token c = next(last_line, "a channel name");
      BvhChannel channel{};
      if (!channel_from_name(c.text, channel)) {
        fail(c.line, "unknown channel '" + std::string(c.text) + "' in joint '" + std::string(name.text) + "'");
      }
      for (BvhChannel seen : skeleton.joints[index].channels) {
        if (seen == channel) fail(c.line, "channel '" + std::string(c.text) + "' repeated");
      }
      skeleton.joints[index].channels.push_back(channel);
    }
    skeleton.channel_count += static_cast<int>(count);

    while (true) {
      const Token t = next(last_line, "}");
      if (t.text == "}") return;
      if (t.text == "JOINT") {
        parse_joint(skeleton, index, last_line);
      } else if (t.text == "End") {
        expect("Site", last_line);
        expect("{", last_line);
        if (skeleton.joints[index].end_site_offset) fail(t.line, "second End Site in a joint");
        skeleton.joints[index].end_site_offset = parse_offset(last_line);
        expect("}", last_line);
      } else {
        fail(t.line, "expected JOINT, End Site or '}', found '" + std::string(t.text) + "'");
      }
    }
  }

  // The next non-empty line from `index` (0-based), or -1.
  int next_nonempty(int index) const {
    for (int i = index; i < static_cast<int>(lines_.size()); ++i) {
      std::vector<Token> t;
      append_tokens(lines_[i], i + 1, t);
      if (!t.empty()) return i;
    }
    return -1;
  }

  void parse_motion(int motion_index, BvhClip& clip) {
    const int last_line = static_cast<int>(lines_.size());
    // "Frames: N"
    const int frames_index = next_nonempty(motion_index + 1);
    if (frames_index < 0) truncated(last_line, "missing 'Frames:' line");
    std::vector<Token> t;
    append_tokens(lines_[frames_index], frames_index + 1, t);
    if (t.size() != 2 || t[0].text != "Frames:") fail(frames_index + 1, "expected 'Frames: <count>'");
    const double frames_value = number(t[1], "Frames");
    if (frames_value < 1 || frames_value != std::floor(frames_value) || frames_value > 1e9) {
      fail(frames_index + 1, "Frames must be a positive integer, got '" + std::string(t[1].text) + "'");
    }
    const auto frame_count = static_cast<std::size_t>(frames_value);

    // "Frame Time: dt"
    const int time_index = next_nonempty(frames_index + 1);
    if (time_index < 0) truncated(last_line, "missing 'Frame Time:' line");
    t.clear();
    append_tokens(lines_[time_index], time_index + 1, t);
    if (t.size() != 3 || t[0].text != "Frame" || t[1].text != "Time:") {
      fail(time_index + 1, "expected 'Frame Time: <seconds>'");
    }
    clip.frame_time_s = number(t[2], "Frame Time");
    if (!(clip.frame_time_s > 0)) {
      fail(time_index + 1, "Frame Time must be > 0, got '" + std::string(t[2].text) + "'");
    }

    const BvhSkeleton& skeleton = clip.skeleton;
    std::vector<double> values(static_cast<std::size_t>(skeleton.channel_count));
    clip.frames.reserve(std::min<std::size_t>(frame_count, lines_.size()));
    int index = time_index + 1;
    for (std::size_t f = 0; f < frame_count; ++f) {
      // Blank lines between frames are tolerated; a frame line must hold every channel.
      index = next_nonempty(index);
      if (index < 0) {
        truncated(last_line, "only " + std::to_string(f) + " of " + std::to_string(frame_count) + " frame lines");
      }
      t.clear();
      append_tokens(lines_[index], index + 1, t);
      if (t.size() != values.size()) {
        fail(index + 1, "frame " + std::to_string(f) + " has " + std::to_string(t.size()) +
                            " values, the hierarchy declares " + std::to_string(values.size()) + " channels");
      }
      for (std::size_t k = 0; k < values.size(); ++k) values[k] = number(t[k], "channel value");
      clip.frames.push_back(decode(skeleton, values));
      ++index;
    }
    const int extra = next_nonempty(index);
    if (extra >= 0) {
      fail(extra + 1, "more frame lines than 'Frames: " + std::to_string(frame_count) + "'");
    }
  }

  static BvhLocalPose decode(const BvhSkeleton& skeleton, const std::vector<double>& values) {
    BvhLocalPose pose;
    pose.parent_from_joint.reserve(skeleton.joints.size());
    pose.translation.reserve(skeleton.joints.size());
    for (const BvhJoint& joint : skeleton.joints) {
      Quat rotation = Quat::Identity();
      Vec3 translation = Vec3::Zero();
      for (std::size_t k = 0; k < joint.channels.size(); ++k) {
        const double v = values[static_cast<std::size_t>(joint.first_channel) + k];
        const double rad = v * EIGEN_PI / 180.0;
        switch (joint.channels[k]) {
          case BvhChannel::kXposition: translation.x() += v; break;
          case BvhChannel::kYposition: translation.y() += v; break;
          case BvhChannel::kZposition: translation.z() += v; break;
          case BvhChannel::kXrotation: rotation = rotation * Quat(Eigen::AngleAxisd(rad, Vec3::UnitX())); break;
          case BvhChannel::kYrotation: rotation = rotation * Quat(Eigen::AngleAxisd(rad, Vec3::UnitY())); break;
          case BvhChannel::kZrotation: rotation = rotation * Quat(Eigen::AngleAxisd(rad, Vec3::UnitZ())); break;
        }
      }
      pose.parent_from_joint.push_back(rotation.normalized());
      pose.translation.push_back(translation);
    }
    return pose;
  }

  std::string source_;
  std::vector<std::string_view> lines_;
  std::vector<Token> tokens_;
  std::size_t pos_ = 0;
  int motion_index_ = -1;  // 0-based line index of MOTION, -1 when the file has none
};

void check_pose_matches(const BvhSkeleton& skeleton, const BvhLocalPose& pose) {
  const std::size_t n = skeleton.joints.size();
  if (pose.parent_from_joint.size() != n || pose.translation.size() != n) {
    throw_invalid("bvh_pose", "pose has " + std::to_string(pose.parent_from_joint.size()) + " rotations and " +
                                  std::to_string(pose.translation.size()) + " translations for a skeleton of " +
                                  std::to_string(n) + " joints");
  }
}

}  // namespace

int BvhSkeleton::find(std::string_view name) const {
  for (std::size_t i = 0; i < joints.size(); ++i) {
    if (joints[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

BvhClip parse_bvh(std::string_view text, const std::string& source_name) { return Parser(text, source_name).parse(); }

BvhClip load_bvh(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(ErrorCode::kNotFound, path.string(), "cannot open BVH file");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw Error(ErrorCode::kDataLoss, path.string(), "read error");
  return parse_bvh(buffer.str(), path.filename().string());
}

Quat W_from_bvh_world() { return Quat(Eigen::AngleAxisd(EIGEN_PI / 2.0, Vec3::UnitX())); }

BvhWorldPose forward_kinematics(const BvhSkeleton& skeleton, const BvhLocalPose& pose, double metres_per_unit) {
  check_pose_matches(skeleton, pose);
  require_positive(metres_per_unit, "metres_per_unit");
  const std::size_t n = skeleton.joints.size();
  std::vector<Quat> M_from_joint(n);
  std::vector<Vec3> p_M(n);
  for (std::size_t i = 0; i < n; ++i) {
    const BvhJoint& joint = skeleton.joints[i];
    const Vec3 local = joint.offset + pose.translation[i];
    if (joint.parent < 0) {
      M_from_joint[i] = pose.parent_from_joint[i];
      p_M[i] = local;
    } else {
      const auto parent = static_cast<std::size_t>(joint.parent);
      M_from_joint[i] = (M_from_joint[parent] * pose.parent_from_joint[i]).normalized();
      p_M[i] = p_M[parent] + M_from_joint[parent] * local;
    }
  }
  const Quat W_from_M = W_from_bvh_world();
  BvhWorldPose out;
  out.W_from_joint.resize(n);
  out.p_W_m.resize(n);
  out.end_site_p_W_m.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    out.W_from_joint[i] = W_from_M * M_from_joint[i];
    out.p_W_m[i] = metres_per_unit * (W_from_M * p_M[i]);
    if (const auto& end = skeleton.joints[i].end_site_offset) {
      out.end_site_p_W_m[i] = metres_per_unit * (W_from_M * (p_M[i] + M_from_joint[i] * *end));
    }
  }
  return out;
}

BvhClip resample(const BvhClip& clip, double rate_hz) {
  require_positive(rate_hz, "rate_hz");
  if (clip.frames.empty()) throw_invalid("clip.frames", "clip has no frames");
  if (!(clip.frame_time_s > 0)) throw_invalid("clip.frame_time_s", "must be > 0");
  for (const BvhLocalPose& pose : clip.frames) check_pose_matches(clip.skeleton, pose);

  BvhClip out;
  out.skeleton = clip.skeleton;
  out.frame_time_s = 1.0 / rate_hz;
  const double duration = clip.duration_s();
  // A tiny tolerance so that a duration that is an exact multiple of the new period keeps its
  // last frame despite rounding.
  const auto count = static_cast<std::size_t>(std::floor(duration * rate_hz + 1e-9)) + 1;
  out.frames.reserve(count);
  const std::size_t last = clip.frames.size() - 1;
  for (std::size_t k = 0; k < count; ++k) {
    const double position = std::min(static_cast<double>(k) / rate_hz / clip.frame_time_s, static_cast<double>(last));
    const auto i0 = std::min(static_cast<std::size_t>(std::floor(position)), last);
    const std::size_t i1 = std::min(i0 + 1, last);
    const double u = position - static_cast<double>(i0);
    const BvhLocalPose& a = clip.frames[i0];
    const BvhLocalPose& b = clip.frames[i1];
    BvhLocalPose pose;
    pose.parent_from_joint.resize(a.parent_from_joint.size());
    pose.translation.resize(a.translation.size());
    for (std::size_t j = 0; j < a.parent_from_joint.size(); ++j) {
      // Eigen's slerp takes the shortest arc (it flips b when the dot product is negative).
      pose.parent_from_joint[j] = a.parent_from_joint[j].slerp(u, b.parent_from_joint[j]).normalized();
      pose.translation[j] = (1.0 - u) * a.translation[j] + u * b.translation[j];
    }
    out.frames.push_back(std::move(pose));
  }
  return out;
}

}  // namespace posefuse::sim
