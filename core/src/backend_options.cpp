// The backends' string form, read and written in this one place.
#include <algorithm>
#include <charconv>

#include "rtcd/backend_options.hpp"
#include "rtcd/error.hpp"

namespace rtcd {
namespace {

constexpr BackendKind kKinds[] = {BackendKind::automatic, BackendKind::basic, BackendKind::embree, BackendKind::opencl,
                                  BackendKind::opencl_basic};

bool on_devices(BackendKind kind) { return kind == BackendKind::opencl || kind == BackendKind::opencl_basic; }

std::string expected(BackendKind kind) {
  switch (kind) {
    case BackendKind::embree:
      return "embree takes threads=N and isa=NAME";
    case BackendKind::opencl:
    case BackendKind::opencl_basic:
      return std::string(to_string(kind)) + " takes threads=N, gpu, cpu, devices=0,1, layout=grid and layout=compact";
    default:
      return std::string(to_string(kind)) + " takes threads=N";
  }
}

// A whole non-negative decimal number, or -1.
int number(std::string_view text) {
  int value = -1;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  return error == std::errc() && end == text.data() + text.size() && !text.empty() && value >= 0 ? value : -1;
}

}  // namespace

const char* to_string(BackendKind kind) {
  switch (kind) {
    case BackendKind::automatic:
      return "auto";
    case BackendKind::basic:
      return "basic";
    case BackendKind::embree:
      return "embree";
    case BackendKind::opencl:
      return "opencl";
    case BackendKind::opencl_basic:
      return "opencl-basic";
  }
  return "?";
}

BackendOptions BackendOptions::parse(std::string_view text) {
  BackendOptions o;
  const std::string whole(text);
  auto bad = [&](const std::string& why) { return BackendError("backend '" + whole + "': " + why); };
  const size_t colon = text.find(':');
  const std::string_view kind = text.substr(0, colon);
  const auto* found =
      std::find_if(std::begin(kKinds), std::end(kKinds), [&](BackendKind k) { return kind == rtcd::to_string(k); });
  if (found == std::end(kKinds))
    throw bad("unknown backend '" + std::string(kind) + "' (auto, basic, embree, opencl, opencl-basic)");
  o.kind = *found;
  std::string_view rest = colon == std::string_view::npos ? std::string_view() : text.substr(colon + 1);
  if (colon != std::string_view::npos && rest.empty()) throw bad("nothing after ':'");
  while (!rest.empty()) {
    const size_t next = rest.find(':');
    const std::string_view option = rest.substr(0, next);
    rest = next == std::string_view::npos ? std::string_view() : rest.substr(next + 1);
    const size_t equals = option.find('=');
    const std::string_view key = option.substr(0, equals);
    const std::string_view value = equals == std::string_view::npos ? std::string_view() : option.substr(equals + 1);
    const bool has_value = equals != std::string_view::npos;
    auto unknown = [&] { return bad("unknown option '" + std::string(option) + "' (" + expected(o.kind) + ")"); };
    if (key == "threads" && has_value) {
      o.threads = number(value);
      if (o.threads < 1) throw bad("threads takes a whole number of at least 1, not '" + std::string(value) + "'");
    } else if (o.kind == BackendKind::embree && key == "isa" && has_value && !value.empty()) {
      o.isa = value;
    } else if (on_devices(o.kind) && (option == "gpu" || option == "cpu")) {
      o.device_type = option == "gpu" ? DeviceType::gpu : DeviceType::cpu;
    } else if (on_devices(o.kind) && (option == "layout=grid" || option == "layout=compact")) {
      o.layout = option == "layout=grid" ? DeviceLayout::grid : DeviceLayout::compact;
    } else if (on_devices(o.kind) && key == "devices" && has_value) {
      o.devices.clear();
      for (std::string_view list = value;;) {
        const size_t comma = list.find(',');
        const std::string_view item = list.substr(0, comma);
        const int index = number(item);
        if (index < 0) throw bad("bad device index '" + std::string(item) + "'");
        o.devices.push_back(index);
        if (comma == std::string_view::npos) break;
        list = list.substr(comma + 1);
      }
    } else {
      throw unknown();
    }
  }
  o.validate();  // what the syntax leaves open: a device listed twice
  return o;
}

std::string BackendOptions::to_string() const {
  std::string s = rtcd::to_string(kind);
  if (device_type != DeviceType::any) s += device_type == DeviceType::gpu ? ":gpu" : ":cpu";
  for (size_t i = 0; i < devices.size(); ++i) s += (i ? "," : ":devices=") + std::to_string(devices[i]);
  if (layout != DeviceLayout::by_mode) s += layout == DeviceLayout::grid ? ":layout=grid" : ":layout=compact";
  if (!isa.empty()) s += ":isa=" + isa;
  if (threads > 0) s += ":threads=" + std::to_string(threads);
  return s;
}

std::string BackendOptions::name() const {
  BackendOptions named = *this;
  named.threads = 0;
  return named.to_string();
}

void BackendOptions::validate() const {
  auto bad = [&](const std::string& why) { return BackendError("backend " + std::string(rtcd::to_string(kind)) + ": " + why); };
  if (threads < 0) throw bad("threads is negative (" + std::to_string(threads) + ")");
  if (!isa.empty() && kind != BackendKind::embree) throw bad("only embree takes an instruction set");
  if (!on_devices(kind) && (device_type != DeviceType::any || !devices.empty() || layout != DeviceLayout::by_mode))
    throw bad("device type, devices and layout are OpenCL options");
  for (size_t i = 0; i < devices.size(); ++i) {
    if (devices[i] < 0) throw bad("device index " + std::to_string(devices[i]) + " is negative");
    if (std::find(devices.begin(), devices.begin() + i, devices[i]) != devices.begin() + i)
      throw bad("device " + std::to_string(devices[i]) + " twice");
  }
}

}  // namespace rtcd
