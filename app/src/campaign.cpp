// A validation campaign's directory and the runner that spreads shards over
// ranks (see campaign.hpp).
#include "campaign.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "commit.hpp"
#include "rtcd/backend_options.hpp"
#include "rtcd/error.hpp"

namespace rtcd::app {
namespace {

namespace fs = std::filesystem;

const char* kFormat = "rtcd-validate-campaign-1";

// Test hook: RTCD_CAMPAIGN_KILL=after:K kills this process with SIGKILL
// once it has stored K shards; inside:K while it writes shard K+1, half
// written. The campaign tests resume from both.
struct KillHook {
  bool inside = false;
  long after = -1;
};
KillHook kill_hook() {
  KillHook hook;
  const char* text = std::getenv("RTCD_CAMPAIGN_KILL");
  if (!text) return hook;
  const std::string s = text;
  const auto colon = s.find(':');
  if (colon == std::string::npos) throw UsageError("RTCD_CAMPAIGN_KILL is after:K or inside:K, not '" + s + "'");
  hook.inside = s.substr(0, colon) == "inside";
  hook.after = std::strtol(s.c_str() + colon + 1, nullptr, 10);
  return hook;
}

void fail_io(const fs::path& path, const char* what) {
  throw UsageError("cannot " + std::string(what) + " '" + path.string() + "': " + std::strerror(errno));
}

// Write, fsync, rename, fsync the directory: the file is whole or absent.
void write_atomically(const fs::path& path, const std::string& text, bool die_half_written = false) {
  const fs::path tmp = path.string() + ".tmp." + std::to_string(getpid());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) fail_io(tmp, "create");
  const size_t length = die_half_written ? text.size() / 2 : text.size();
  for (size_t done = 0; done < length;) {
    const ssize_t n = ::write(fd, text.data() + done, length - done);
    if (n < 0) fail_io(tmp, "write");
    done += size_t(n);
  }
  if (::fsync(fd) != 0) fail_io(tmp, "sync");
  if (die_half_written) std::raise(SIGKILL);
  ::close(fd);
  if (std::rename(tmp.c_str(), path.c_str()) != 0) fail_io(path, "rename into");
  const int dir = ::open(path.parent_path().c_str(), O_RDONLY | O_DIRECTORY);
  if (dir >= 0) {
    ::fsync(dir);
    ::close(dir);
  }
}

nlohmann::json read_json(const fs::path& path, const std::string& what) {
  std::ifstream in(path);
  if (!in) throw UsageError("cannot read " + what + " '" + path.string() + "'");
  std::stringstream text;
  text << in.rdbuf();
  try {
    return nlohmann::json::parse(text.str());
  } catch (const nlohmann::json::exception& e) {
    throw UsageError(what + " '" + path.string() + "' is corrupt (" + e.what() + ")");
  }
}

// The first key whose value differs between what a campaign was made with
// and what it is asked to run, as "key: was X, now Y".
std::string difference(const nlohmann::json& was, const nlohmann::json& now, const std::string& prefix = "") {
  if (was.is_object() && now.is_object()) {
    for (const auto& [key, value] : now.items()) {
      const auto it = was.find(key);
      if (it == was.end()) return prefix + key + ": absent there, now " + value.dump();
      if (const std::string d = difference(*it, value, prefix + key + "."); !d.empty()) return d;
    }
    for (const auto& [key, value] : was.items())
      if (!now.contains(key)) return prefix + key + ": was " + value.dump() + ", now absent";
    return "";
  }
  return was == now ? "" : prefix.substr(0, prefix.size() - (prefix.empty() ? 0 : 1)) + ": was " + was.dump() +
                               ", now " + now.dump();
}

}  // namespace

std::string run_name(const validation::Family& family, const validation::RunOptions& options) {
  return family.name + "." + to_string(BackendOptions::parse(options.backend).kind) + "." +
         validation::to_string(options.mode);
}

Campaign::Campaign(fs::path dir, nlohmann::json arguments, size_t shard_pairs, double hours, const Ranks& ranks)
    : dir_(std::move(dir)), shard_pairs_(shard_pairs), hours_(hours) {
  if (shard_pairs == 0) throw UsageError("a campaign needs at least one pair per shard");
  if (!(hours >= 0.0)) throw UsageError("--hours must not be negative");
  arguments["shard_pairs"] = shard_pairs;
  identity_ = {{"format", kFormat}, {"commit", kCommit}, {"arguments", std::move(arguments)}};
  const fs::path file = dir_ / "campaign.json";
  if (ranks.reports() && !fs::exists(file)) {
    std::error_code ec;
    if (fs::exists(dir_) && !fs::is_empty(dir_, ec))
      throw UsageError("'" + dir_.string() + "' is not a campaign's directory (no campaign.json) and is not empty");
    fs::create_directories(dir_ / "runs", ec);
    if (ec) throw UsageError("cannot create '" + dir_.string() + "': " + ec.message());
    write_atomically(file, identity_.dump(2) + "\n");
  }
  if (ranks.reports()) {
    // What a killed writer left half written; no rank writes before the barrier.
    std::error_code ec;
    for (auto it = fs::recursive_directory_iterator(dir_, ec); !ec && it != fs::recursive_directory_iterator();
         it.increment(ec))
      if (it->path().filename().string().find(".json.tmp.") != std::string::npos) fs::remove(it->path(), ec);
  }
  ranks.barrier();
  const nlohmann::json was = read_json(file, "the campaign file");
  if (was.value("format", "") != kFormat)
    throw UsageError("'" + file.string() + "' is not a campaign file of this kind (format " +
                     was.value("format", std::string("none")) + ")");
  if (const std::string d = difference(was, identity_); !d.empty())
    throw UsageError("the campaign in '" + dir_.string() + "' was made with other arguments or by another build (" +
                     d + "): start it again as it was, or use another directory");
}

fs::path Campaign::shard_path(const std::string& run, size_t k) const {
  std::ostringstream name;
  name << "shard-" << std::setw(6) << std::setfill('0') << k << ".json";
  return dir_ / "runs" / run / name.str();
}

std::vector<size_t> Campaign::missing(const std::string& run, size_t shards) const {
  std::vector<size_t> out;
  for (size_t k = 0; k < shards; ++k)
    if (!fs::exists(shard_path(run, k))) out.push_back(k);
  return out;
}

validation::Shard Campaign::load(const std::string& run, size_t k, size_t first, size_t count) const {
  const fs::path path = shard_path(run, k);
  const nlohmann::json j = read_json(path, "the shard file");
  const auto refuse = [&](const std::string& why) {
    return UsageError("the shard file '" + path.string() + "' " + why +
                      ": delete it to run that shard again");
  };
  if (!j.is_object() || j.value("run", "") != run || j.value("shard", size_t(-1)) != k)
    throw refuse("is not shard " + std::to_string(k) + " of run " + run);
  if (j.value("campaign", nlohmann::json()) != identity_)
    throw refuse("was written by another campaign");
  validation::Shard shard;
  try {
    shard = validation::shard_from_json(j.value("result", nlohmann::json()));
  } catch (const UsageError& e) {
    throw refuse(std::string("is malformed (") + e.what() + ")");
  }
  if (shard.first != first || shard.pairs.size() != count)
    throw refuse("holds pairs " + std::to_string(shard.first) + " to " +
                 std::to_string(shard.first + shard.pairs.size()) + ", not " + std::to_string(first) + " to " +
                 std::to_string(first + count));
  return shard;
}

void Campaign::store(const std::string& run, size_t k, const validation::Shard& shard) {
  static const KillHook hook = kill_hook();
  const fs::path path = shard_path(run, k);
  std::error_code ec;
  fs::create_directories(path.parent_path(), ec);
  if (ec) throw UsageError("cannot create '" + path.parent_path().string() + "': " + ec.message());
  const nlohmann::json j = {{"run", run}, {"shard", k}, {"campaign", identity_}, {"result", validation::to_json(shard)}};
  const bool die_inside = hook.inside && long(stored_) == hook.after;
  write_atomically(path, j.dump() + "\n", die_inside);
  ++stored_;
  if (!hook.inside && long(stored_) == hook.after) std::raise(SIGKILL);
}

bool Campaign::out_of_time() const {
  return hours_ > 0.0 &&
         std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count() > hours_ * 3600.0;
}

void Campaign::write_report(const nlohmann::json& report) const {
  write_atomically(dir_ / "report.json", report.dump(2) + "\n");
}

namespace {

std::string join(const std::vector<size_t>& v) {
  std::string s;
  for (size_t x : v) s += std::to_string(x) + " ";
  return s;
}

std::vector<size_t> split(const std::string& s) {
  std::vector<size_t> v;
  std::istringstream in(s);
  for (size_t x; in >> x;) v.push_back(x);
  return v;
}

}  // namespace

std::optional<std::vector<validation::Shard>> SpreadShards::run(const validation::Family& family,
                                                                const validation::RunOptions& options) const {
  if (campaign) return run_in_campaign(family, options);
  // One process: its one shard as it is, never through JSON.
  if (ranks.size() == 1) return std::vector{validation::run_shard(family, options, 0, options.pairs)};
  // One shard a rank, as even as the pairs allow.
  const size_t n = options.pairs, size = size_t(ranks.size()), r = size_t(ranks.rank());
  const size_t first = n * r / size, end = n * (r + 1) / size;
  nlohmann::json mine = nullptr;
  if (end > first) mine = validation::to_json(validation::run_shard(family, options, first, end - first));
  const std::vector<std::string> all = ranks.gather(mine.dump());
  if (!ranks.reports()) return std::nullopt;
  std::vector<validation::Shard> shards;
  for (const std::string& text : all)
    if (const auto j = nlohmann::json::parse(text); !j.is_null()) shards.push_back(validation::shard_from_json(j));
  return shards;
}

std::optional<std::vector<validation::Shard>> SpreadShards::run_in_campaign(
    const validation::Family& family, const validation::RunOptions& options) const {
  const std::string run = run_name(family, options);
  const size_t cut = campaign->shard_pairs(), count = (options.pairs + cut - 1) / cut;
  const auto pairs_of = [&](size_t k) { return std::min(cut, options.pairs - k * cut); };
  // Rank 0 lists what is missing, so every rank shares out the same list.
  const std::vector<size_t> missing =
      split(ranks.broadcast(ranks.reports() ? join(campaign->missing(run, count)) : ""));
  for (size_t i = size_t(ranks.rank()); i < missing.size(); i += size_t(ranks.size())) {
    if (campaign->out_of_time()) break;
    const size_t k = missing[i];
    campaign->store(run, k, validation::run_shard(family, options, k * cut, pairs_of(k)));
  }
  ranks.barrier();
  if (!ranks.reports()) return std::nullopt;
  const size_t left = campaign->missing(run, count).size();
  // What a resume reused: the shards kept from before, and those run now.
  std::fprintf(stderr, "campaign %s: %zu of %zu shards kept from before, %zu run now\n", run.c_str(),
               count - missing.size(), count, missing.size() - left);
  if (left > 0) {
    unfinished_ = true;
    return std::nullopt;
  }
  std::vector<validation::Shard> shards;
  for (size_t k = 0; k < count; ++k) shards.push_back(campaign->load(run, k, k * cut, pairs_of(k)));
  return shards;
}

const Ranks& one_process() {
  static const Ranks ranks;
  return ranks;
}

}  // namespace rtcd::app
