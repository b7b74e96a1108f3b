// The OpenCL executor. Shapes are copied to every device once (at the first
// step after they are added), the bodies' poses once a step; each step's
// pair-directions are spread over the devices (a pair that walks stays on
// the device holding its tracked rays; the others go to the least loaded
// by items to search), each device with its own queue, and all devices run
// at once:
//   1. rtcd_pair_list: the batch's pair setups from what was sent (a full
//      pair's bodies and flags, 12 bytes; a walking pair's reference to its
//      row of last step's pair table, or its 32-byte setup) and a walking
//      batch's first items; rtcd_prepare: each job made from its pair's
//      setup (both directions: the pair's motion from the poses of the last
//      step and this one, limits from it, parameters; the bodies' shapes
//      are on the device) and its frame from its bodies' poses, by the
//      host's own functions (kernel/motion.h, kernel/limits.h,
//      kernel/job.h, kernel/frame.h); a full job's items are the source-tree
//      leaves near its candidate box, which it searches there
//      (kernel/near.h, the CPU executors' search), counts into room for the
//      batch's items (an atomic count; room the host guessed, and a batch
//      that outgrows it runs again) and lists in item order. Then
//      rtcd_select: every possible ray (source item: a vertex or an edge,
//      or tracked ray) placed in the target's frame in double and flagged
//      when it is a candidate (the host makes the frames, searches and
//      places the rays when a device lacks fp64);
//   2. rtcd_count and rtcd_offsets: per job, a prefix sum over the flags,
//      then one over the jobs, so the candidates form a compacted list in
//      the CPU's order, laid out on the device;
//   3. rtcd_scatter and rtcd_trace: candidates to their places, then one
//      work-item per ray running kernel/trace.h;
//   4. rtcd_tallies, rtcd_total and rtcd_lay_out: each job's outcomes are
//      counted there (kernel/tally.h); the rays it goes on tracking stay on
//      the device for the next step's walks, one job after another, and
//      those that report (contacts, predictive rays) are laid out by job,
//      each naming its job. After one wait the host reads the counters (and
//      a full batch's item count), 8 bytes a job (its kept rays and kept
//      vertex rays) and the reports whole (up to a bound guessed from each
//      pair's reports the step before; past it, a second read and wait),
//      and builds each job's kept outcomes in its slot: the reports in their
//      places, placeholders (kind and edge) for the rest, so the step is in
//      job order (poses and setups go up; no other outcome comes down).
//   5. The kept rays' walk starts are read back on a second queue that
//      nothing waits for (bytes_recovery), unless the host reorders a
//      pair's rays (recover) or the CPU takes a step over from a fault.
// The grid layout (iterative batches) does 1 and 3 in one kernel,
// rtcd_trace_items: each item placed and, if a candidate, traced in place.
// Any fault (no platform, a failed build, out of memory, a device error)
// is reported once and the step, and every later one, runs on the CPU
// executor from the same jobs, so the result does not change.
#include "opencl_backend.hpp"

#include <CL/opencl.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <iostream>
#include <limits>
#include <mutex>
#include <utility>

#include "device_types.h"
#include "rtcd/error.hpp"
#include "rtcd/kernel/motion.h"
#include "runtime.hpp"
#include "shape_data.hpp"

namespace rtcd::opencl {
namespace {

static_assert(sizeof(rtcd_vec3) == sizeof(Eigen::Vector3f));
// The kernels read the buffers with OpenCL C's layout of the same structs:
// only 4-byte members (8 in rtcd_frame), so no padding differs.
static_assert(sizeof(rtcd_outcome) == 32 && sizeof(rtcd_candidate) == 40 && sizeof(rtcd_trace_params) == 72);
static_assert(sizeof(rtcd_device_job) == 96 && sizeof(rtcd_device_shape) == 68 && sizeof(rtcd_bvh_node) == 36);
static_assert(sizeof(rtcd_report) == 40 && sizeof(rtcd_job_summary) == 8 && sizeof(rtcd_tally) == 8 * 24);
static_assert(sizeof(rtcd_frame) == 144 && alignof(rtcd_frame) == 8 &&
              sizeof(rtcd_bvh_wide_node) == 32 * RTCD_BVH_WIDTH);
static_assert(sizeof(rtcd_job_setup) == 64 && sizeof(rtcd_pair_setup) == 32 && alignof(rtcd_pair_setup) == 4 &&
              sizeof(rtcd_shape_scale) == 32 && sizeof(rtcd_limit_settings) == 24 &&
              sizeof(rtcd_pose) == 56 &&
              sizeof(rtcd_box) == 48 && sizeof(rtcd_shape_traits) == 16);

static_assert(RTCD_PAIR_SETUP_WORDS * sizeof(rtcd_uint) == sizeof(rtcd_pair_setup) &&
              RTCD_PAIR_COUNTS_WORD * sizeof(rtcd_uint) == offsetof(rtcd_pair_setup, item_count) &&
              RTCD_PAIR_REF_WORDS * sizeof(rtcd_uint) == sizeof(rtcd_pair_ref) && alignof(rtcd_pair_ref) == 4 &&
              sizeof(rtcd_full_pair) == 12 && alignof(rtcd_full_pair) == 4 &&
              sizeof(rtcd_distance_grid) == 104 && sizeof(rtcd_source_node) == 36 &&
              RTCD_NO_SLOT == Residence::kNoRecord);
static_assert((RTCD_JOB_ITERATIVE | RTCD_PAIR_EDGES(0) | RTCD_PAIR_EDGES(1) | RTCD_PAIR_MOTION | RTCD_PAIR_RESIDENT) ==
              RTCD_PAIR_MAX_FLAGS);

constexpr size_t kGroupSize = 64;
// A kept outcome's vertex until its walk start is recovered.
constexpr rtcd_uint kPlaceholder = ~rtcd_uint(0);

// A device buffer that keeps its capacity from step to step.
struct GrowingBuffer {
  cl::Buffer buffer;
  size_t bytes = 0;
};

// Device::shapes by name, in upload order: the trace kernels take the
// first kTracedShapeBuffers, after the jobs.
enum ShapeBuffer : size_t {
  kTable, kPositions, kTriangles, kNeighbors, kZeroArea, kNormals, kFoldFaces, kRingFirst, kRing, kNodes, kWide,
  kPrimitives, kOrigins, kDirections, kSourceNodes, kSourceOrder, kLeafItems, kGrids, kGridValues, kBounds, kTraits,
  kScales
};
constexpr size_t kTracedShapeBuffers = kOrigins;

// One batch's share of a device: its jobs, their host-side data and the
// buffers they use. A step's two batches have a lane each, so the full
// batch runs on the device while the walks are set up.
struct Lane {
  GrowingBuffer list, setups, jobs, first_items, frames, near, items_found, item_jobs, vertices, flags, staging, slots,
      counts, first_rays, rays, outcomes;
  GrowingBuffer tallies, laid_out, summaries, total, reports;
  // The jobs it runs (batch indices) and their host-side data.
  std::vector<uint32_t> batch_jobs;
  std::vector<rtcd_device_job> host_jobs;
  std::vector<rtcd_uint> host_first_items, host_counts, host_first_rays;
  std::vector<rtcd_pair_setup> host_setups;  // the device makes the jobs and frames from them (rtcd_prepare)
  // A walking batch's pairs as it sends them (rtcd_pair_list): a reference
  // a pair, then the setups of those not resident; `list` the words sent.
  std::vector<rtcd_pair_ref> host_refs;
  std::vector<rtcd_uint> host_list;
  // A full batch on a device that finds its items (device_counts): its
  // pairs as sent, and its jobs with an overlap to search; room is made for
  // `items` of them (a guess from most_items_per_job, at most item_bound,
  // the searched sources' items), and the device's count comes back
  // (found).
  bool device_counts = false;
  std::vector<rtcd_full_pair> host_full;
  uint32_t searched_jobs = 0;
  uint64_t item_bound = 0;
  double most_items_per_job = 0, last_items_per_job = 0;  // over its past batches, and its last
  // Its kernels over items and rays take them in strides of this many
  // work-items (RTCD_FOR_EACH): its items where the host knows them, else
  // as many as its last batch's a searched job.
  uint32_t launch_items = 0;
  std::vector<rtcd_uint> host_found;  // one
  uint32_t found = 0;
  double pair_motion = 0;  // the last pair's, while its setup is checked (add_direction)
  bool motions = false;    // a pair derives its motion from the last step's poses (RTCD_PAIR_MOTION)
  uint32_t setups_sent = 0;            // after the references
  uint32_t slot_base = RTCD_NO_SLOT;  // its pairs' rows in the step's pair table
  std::vector<rtcd_frame> host_frames;      // the host places the rays: it makes the frames
  std::vector<rtcd_uint> host_near;  // full jobs' near items, where the host places the rays (rtcd_near_item)
  std::vector<rtcd_tracked> host_tracked;
  std::vector<rtcd_candidate> host_rays;
  // What comes back: the batch's counters, a summary a job and the reports
  // by job; the kept rays lie by job from kept_base on (host_first_kept).
  std::vector<rtcd_tally> host_total;  // one
  std::vector<rtcd_job_summary> host_summaries;
  std::vector<rtcd_uint> host_first_kept;
  std::vector<rtcd_report> host_reports;
  std::vector<rtcd_tracked> host_kept;  // the host placed the rays: it reads them whole
  uint32_t items = 0, ray_count = 0, report_count = 0;  // items: room for them where the device counts
  // The reports it expects: its jobs' last where they ran before, and
  // reports_per_item for the items of the others (guessed where the device
  // counts them).
  uint32_t known_reports = 0;
  size_t unknown_items = 0, unknown_jobs = 0;
  // The reports are read before they are counted, up to report_bound
  // (expected_reports).
  uint32_t report_bound = 0;
  double reports_per_item = 0;
  size_t load = 0;
  uint32_t upload_base = 0;  // the batch's uploaded tracked rays in the read buffer
  uint32_t kept_base = 0;    // the batch's kept rays in the written buffer
  cl::Event outcomes_read;   // its last read
  bool pending = false;      // enqueued, not finished
  bool ran = false;          // its counters are this step's
};

// A device's lanes (Device::lanes): its full batch's and its walking batch's.
constexpr size_t kFullLane = 0, kWalkedLane = 1;

struct Device {
  cl::CommandQueue queue;
  cl::Kernel pair_list, prepare, select, count, offsets, scatter, trace, trace_items, tallies, total, lay_out;
  // Shape data, by ShapeBuffer.
  std::vector<cl::Buffer> shapes;
  size_t shapes_uploaded = 0;
  // Every body's pose (rtcd_pose): the step's, and the last step's, from
  // which rtcd_prepare derives the pairs' motions.
  GrowingBuffer poses, before;
  uint64_t poses_written = 0, before_written = 0;  // the steps they are
  GrowingBuffer body_shapes;   // every body's shape, by BodyId
  size_t body_shapes_written = 0;
  // Tracked rays that stay on the device, by step parity: the step's
  // batches append what they keep to one (rtcd_lay_out) while its walks read
  // the other, written the step before, with the rays that came from
  // elsewhere (the host's mirror) appended there.
  GrowingBuffer kept[2];
  uint32_t kept_used[2] = {0, 0};  // room used in each: a compacted batch takes its items' worth
  // The pairs' rows (rtcd_pair_setup: bodies, each direction's kept rays),
  // by step parity as `kept`: a walking pair resident here is sent as a
  // reference to its row of the last step (rtcd_pair_ref).
  GrowingBuffer pair_table[2];
  uint32_t rows_used[2] = {0, 0};
  DeviceWork work;  // this step's, over its batches
  // Commands whose device time is not counted yet (profiling events, kernel
  // or copy); kept until seen finished.
  struct Timed {
    cl::Event event;
    bool kernel;
  };
  std::vector<Timed> timed;
  Lane lanes[2];  // by batch: kFullLane, kWalkedLane
  size_t group_size = 1;
  // The recovery reads: the kept rays' walk starts, by step parity as
  // `kept`, read on a queue of their own that the step never waits for.
  cl::CommandQueue recovery;
  std::vector<rtcd_tracked> recovered[2];
  std::vector<cl::Event> recovering[2];
  size_t early_waits = 0;  // waits for them before begin_step, counted in the step
};

class OpenClExecutor final : public RayExecutor {
 public:
  OpenClExecutor(std::string name, std::shared_ptr<const Runtime> runtime, std::string setup_fault, bool bvh,
                 DeviceLayout layout, OpenClFault fault, CpuFallback fallback)
      : name_(std::move(name)),
        runtime_(std::move(runtime)),
        bvh_(bvh),
        layout_(layout),
        fault_(fault),
        fallback_(std::move(fallback)) {
    if (!setup_fault.empty()) {
      fail(setup_fault);
      return;
    }
    try {
      for (const cl::Device& d : runtime_->devices) {
        Device device;
        device.queue = cl::CommandQueue(runtime_->context, d, CL_QUEUE_PROFILING_ENABLE);
        device.recovery = cl::CommandQueue(runtime_->context, d);
        for (auto& events : device.recovering) events.reserve(2);
        if (runtime_->place_on_device) {
          device.pair_list = cl::Kernel(runtime_->program, "rtcd_pair_list");
          device.prepare = cl::Kernel(runtime_->program, "rtcd_prepare");
          device.select = cl::Kernel(runtime_->program, "rtcd_select");
          device.trace_items = cl::Kernel(runtime_->program, "rtcd_trace_items");
        }
        device.count = cl::Kernel(runtime_->program, "rtcd_count");
        device.offsets = cl::Kernel(runtime_->program, "rtcd_offsets");
        device.scatter = cl::Kernel(runtime_->program, "rtcd_scatter");
        device.trace = cl::Kernel(runtime_->program, "rtcd_trace");
        device.tallies = cl::Kernel(runtime_->program, "rtcd_tallies");
        device.total = cl::Kernel(runtime_->program, "rtcd_total");
        device.lay_out = cl::Kernel(runtime_->program, "rtcd_lay_out");
        device.group_size = kGroupSize;
        for (const cl::Kernel* k :
             {&device.prepare, &device.select, &device.count, &device.offsets, &device.scatter, &device.trace,
              &device.trace_items, &device.tallies, &device.total, &device.lay_out})
          if ((*k)())
            device.group_size = std::min(device.group_size, k->getWorkGroupInfo<CL_KERNEL_WORK_GROUP_SIZE>(d));
        devices_.push_back(std::move(device));
      }
    } catch (const cl::Error& e) {
      fail(describe(e));
    }
  }

  ~OpenClExecutor() override { settle(); }

  void add_shape(std::shared_ptr<const Shape> shape, const ShapeScale& scale) override {
    if (fault_message_.empty()) data_.add(*shape, scale, bvh_);
    if (cpu_) cpu_->add_shape(shape, scale);
    shapes_.push_back(std::move(shape));
    scales_.push_back(scale);
  }

  void add_body(ShapeId shape) override { body_shapes_.push_back(shape); }

  void begin_step(std::span<const rtcd_pose> poses) override {
    ++step_;
    std::swap(last_poses_, poses_);
    poses_.assign(poses.begin(), poses.end());
    on_cpu_ = false;
    for (Device& d : devices_) {
      d.kept_used[step_ % 2] = 0;
      d.rows_used[step_ % 2] = 0;
      d.work = {};
      d.work.waits = std::exchange(d.early_waits, 0);
    }
  }

  void configure(const Config& config) override {
    config_ = config;
    limit_settings_ = limit_settings(config);
    if (cpu_) cpu_->configure(config);
  }

  void execute(RayBatch& batch) override {
    if (fault_message_.empty()) {
      try {
        return run(batch);
      } catch (const cl::Error& e) {
        fail(describe(e) + " during a step");
      } catch (const Error& e) {
        fail(e.what());
      }
    }
    // The CPU takes over from the jobs, the full batch's too when it was
    // still on a device; walks start from the rays the devices kept.
    on_cpu_ = true;
    if (batch.iterative) take_over_walks(batch);
    if (full_ && full_ != &batch) {
      full_->counted = {};
      cpu().execute(*full_);
    }
    full_ = nullptr;
    batch.counted = {};
    cpu().execute(batch);
  }

  void recover(const Residence& residence, std::span<RayOutcome> tracked) override {
    fill_walk_starts(residence, step_, tracked, true);
  }

  void account(StepStats& stats) const override {
    stats.devices.resize(devices_.size());
    for (size_t i = 0; i < devices_.size(); ++i) {
      const DeviceWork& w = stats.devices[i] = devices_[i].work;
      stats.device_launches += w.launches;
      stats.device_writes += w.writes;
      stats.device_reads += w.reads;
      stats.device_waits += w.waits;
      stats.bytes_to_device += w.bytes_to_device;
      stats.bytes_from_device += w.bytes_from_device;
      stats.bytes_recovery += w.bytes_recovery;
      stats.seconds_device_kernels += w.seconds_kernels;
      stats.seconds_device_copies += w.seconds_copies;
    }
    if (on_cpu_) stats.cpu_fallback = fault_message_;
  }

 private:
  // Waits until no device writes into host memory any more; errors are
  // already being handled.
  void settle() {
    for (Device& d : devices_) {
      for (cl::CommandQueue* q : {&d.queue, &d.recovery}) {
        try {
          if ((*q)()) q->finish();
        } catch (...) {
        }
      }
    }
  }

  // The recovery reads of step parity `parity` finished; `early`: before
  // the step's begin_step, so counted in the next step's waits. Throws
  // when one failed: the walk starts are lost.
  static void wait_recovered(Device& d, size_t parity, bool early) {
    for (cl::Event& e : d.recovering[parity]) {
      cl_int status = e.getInfo<CL_EVENT_COMMAND_EXECUTION_STATUS>();
      if (status > CL_COMPLETE) {
        e.wait();
        ++(early ? d.early_waits : d.work.waits);
        status = e.getInfo<CL_EVENT_COMMAND_EXECUTION_STATUS>();
      }
      if (status < 0)
        throw Error("a device could not read back its tracked rays (OpenCL status " + std::to_string(status) + ")");
    }
  }

  // The walk starts of the placeholders this executor left in a direction's
  // kept outcomes, when its devices kept them at step `written`, from the
  // recovery reads (waited for, once a step whoever asks first).
  void fill_walk_starts(const Residence& r, uint64_t written, std::span<RayOutcome> tracked, bool early) {
    if (!runtime_ || !runtime_->place_on_device || r.step == 0 || r.step != written || r.place >= devices_.size())
      return;
    Device& d = devices_[r.place];
    const size_t parity = written % 2;
    {
      std::lock_guard lock(recovering_);
      wait_recovered(d, parity, early);
    }
    const std::vector<rtcd_tracked>& starts = d.recovered[parity];
    const size_t count = std::min<size_t>(r.count, tracked.size());
    if (size_t(r.first) + count > starts.size()) throw Error("tracked rays past a device's recovery read");
    for (size_t k = 0; k < count; ++k) {
      const rtcd_tracked& s = starts[r.first + k];
      tracked[k].vertex = s.vertex;
      tracked[k].triangle = s.triangle;
      tracked[k].entry = s.entry;
    }
  }

  // A walked batch the CPU runs: its jobs' tracked rays that the devices
  // kept last step, with their walk starts, in copies of the executor's.
  void take_over_walks(RayBatch& batch) {
    if (taken_over_.size() < batch.jobs.size()) taken_over_.resize(batch.jobs.size());
    for (size_t j = 0; j < batch.jobs.size(); ++j) {
      RayJob& job = batch.jobs[j];
      if (!job.residence || job.residence->step == 0 || job.residence->step + 1 != step_) continue;
      taken_over_[j].assign(job.tracked.begin(), job.tracked.end());
      fill_walk_starts(*job.residence, step_ - 1, taken_over_[j], false);
      job.tracked = taken_over_[j];
    }
  }

  void fail(const std::string& what) {
    settle();
    fault_message_ = what;
    std::cerr << "rtcd: " << name_ << ": " << what << "; this step and the following run on the CPU ("
              << fallback_.name << ")\n";
  }

  RayExecutor& cpu() {
    if (!cpu_) {
      cpu_ = make_cpu_executor(fallback_.tracers());
      cpu_->configure(config_);
      for (size_t i = 0; i < shapes_.size(); ++i) cpu_->add_shape(shapes_[i], scales_[i]);
    }
    return *cpu_;
  }

  cl::Buffer allocate(size_t bytes, cl_mem_flags flags, void* host = nullptr) {
    if (fault_ == OpenClFault::out_of_memory)
      throw cl::Error(CL_MEM_OBJECT_ALLOCATION_FAILURE, "clCreateBuffer (injected fault)");
    return cl::Buffer(runtime_->context, flags, bytes, host);
  }

  template <class T>
  cl::Buffer upload_once(const std::vector<T>& v) {
    if (v.empty()) return allocate(sizeof(T), CL_MEM_READ_ONLY);  // no zero-size buffers in OpenCL
    return allocate(v.size() * sizeof(T), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, const_cast<T*>(v.data()));
  }

  void upload_shapes(Device& d) {
    if (d.shapes_uploaded == data_.table.size()) return;
    // In ShapeBuffer's order.
    d.shapes = {upload_once(data_.table),      upload_once(data_.positions),  upload_once(data_.triangles),
                upload_once(data_.neighbors),  upload_once(data_.zero_area),  upload_once(data_.normals),
                upload_once(data_.fold_faces), upload_once(data_.ring_first), upload_once(data_.ring),
                upload_once(data_.nodes),      upload_once(data_.wide),       upload_once(data_.primitives),
                upload_once(data_.origins),    upload_once(data_.directions), upload_once(data_.source_nodes),
                upload_once(data_.source_order), upload_once(data_.leaf_items), upload_once(data_.grids),
                upload_once(data_.grid_values),
                upload_once(data_.bounds),     upload_once(data_.traits),     upload_once(data_.scales)};
    d.shapes_uploaded = data_.table.size();
  }

  void reserve(GrowingBuffer& b, size_t bytes) {
    bytes = std::max<size_t>(bytes, 64);
    if (bytes <= b.bytes) return;
    bytes = std::max(bytes, b.bytes + b.bytes / 2);
    b.buffer = allocate(bytes, CL_MEM_READ_WRITE);
    b.bytes = bytes;
  }

  // Room for `count` records of T in all, the first `used` kept (copied on
  // the device when the buffer grows).
  template <class T>
  void reserve_keeping(Device& d, GrowingBuffer& b, size_t count, size_t used) {
    if (std::max<size_t>(count * sizeof(T), 64) <= b.bytes) return;
    const cl::Buffer old = b.buffer;
    reserve(b, count * sizeof(T));
    if (used > 0) d.queue.enqueueCopyBuffer(old, b.buffer, 0, 0, used * sizeof(T), nullptr, timed(d, false));
  }

  // A new command's event, to be timed once it has finished.
  static cl::Event* timed(Device& d, bool kernel) {
    return &d.timed.emplace_back(Device::Timed{cl::Event(), kernel}).event;
  }

  // The host blocks until the command of `done` has finished.
  static void wait(Device& d, const cl::Event& done) {
    done.wait();
    ++d.work.waits;
  }

  // The device time of every timed command that has finished, into the
  // step's work; the others stay for a later step.
  static void collect(Device& d) {
    size_t kept = 0;
    for (size_t i = 0; i < d.timed.size(); ++i) {
      Device::Timed& t = d.timed[i];
      const cl_int status = t.event.getInfo<CL_EVENT_COMMAND_EXECUTION_STATUS>();
      if (status > CL_COMPLETE) {
        if (kept != i) d.timed[kept] = std::move(t);
        ++kept;
        continue;
      }
      if (status < 0) continue;  // failed: the fault is reported where it struck
      const double seconds = 1e-9 * double(t.event.getProfilingInfo<CL_PROFILING_COMMAND_END>() -
                                           t.event.getProfilingInfo<CL_PROFILING_COMMAND_START>());
      (t.kernel ? d.work.seconds_kernels : d.work.seconds_copies) += seconds;
    }
    d.timed.resize(kept);
  }

  // `v` (a vector or span) into `b` from element `offset` on; `b` holds
  // them already. The host memory must stay as it is until the step ends.
  template <class V>
  void write_at(Device& d, GrowingBuffer& b, const V& v, size_t offset) {
    if (v.empty()) return;
    const size_t bytes = v.size() * sizeof(v[0]);
    d.queue.enqueueWriteBuffer(b.buffer, CL_FALSE, offset * sizeof(v[0]), bytes, v.data(), nullptr, timed(d, false));
    d.work.bytes_to_device += bytes;
    ++d.work.writes;
  }

  template <class V>
  void write(Device& d, GrowingBuffer& b, const V& v) {
    reserve(b, v.size() * sizeof(v[0]));
    write_at(d, b, v, 0);
  }

  // Elements [at + first, at + first + count) of `b` into `v` from `first`
  // on; `v` holds them.
  template <class T>
  void read(Device& d, const GrowingBuffer& b, size_t at, std::vector<T>& v, size_t first, size_t count,
            cl::Event* done = nullptr) {
    cl::Event* event = timed(d, false);
    d.queue.enqueueReadBuffer(b.buffer, CL_FALSE, (at + first) * sizeof(T), count * sizeof(T), v.data() + first,
                              nullptr, event);
    if (done) *done = *event;
    d.work.bytes_from_device += count * sizeof(T);
    ++d.work.reads;
  }

  template <class T>
  void read(Device& d, const GrowingBuffer& b, std::vector<T>& v) {
    read(d, b, 0, v, 0, v.size());
  }

  // The job's tracked rays are on a device already: they were kept there
  // the step before (the host's mirror holds the same rays).
  bool resident(const RayJob& job) const {
    return runtime_->place_on_device && job.iterative && job.residence && job.residence->step != 0 &&
           job.residence->step + 1 == step_ && job.residence->place < devices_.size();
  }

  // A pair's two jobs run on one device: the one it ran on before, while it
  // stays in the broad phase (its residences say which; walking jobs find
  // their kept rays there), or, for a new pair, the device with the fewest
  // expected rays so far. Into each device's lane `which`.
  void assign(size_t which, std::span<const RayJob> jobs, const Config& config) {
    for (Device& d : devices_) {
      Lane& lane = d.lanes[which];
      lane.batch_jobs.clear();
      lane.host_jobs.clear();
      lane.host_first_items.clear();
      lane.host_setups.clear();
      lane.host_refs.clear();
      lane.setups_sent = 0;
      lane.device_counts = runtime_->place_on_device && which == kFullLane;
      lane.host_full.clear();
      lane.searched_jobs = 0;
      lane.item_bound = 0;
      lane.found = 0;
      lane.motions = false;
      lane.slot_base = RTCD_NO_SLOT;
      lane.host_frames.clear();
      lane.host_near.clear();
      lane.host_tracked.clear();
      lane.items = 0;
      lane.ray_count = 0;
      lane.load = 0;
      lane.upload_base = runtime_->place_on_device ? d.kept_used[(step_ + 1) % 2] : 0;
      lane.known_reports = 0;
      lane.unknown_items = 0;
      lane.unknown_jobs = 0;
      lane.pending = false;
      lane.ran = false;
    }
    // Jobs 2i and 2i + 1 are one pair's (RayBatch).
    const auto placed = [&](uint32_t j) -> const Residence* {
      for (uint32_t k : {j, j + 1})
        if (const Residence* r = jobs[k].residence; r && r->placed && r->place < devices_.size()) return r;
      return nullptr;
    };
    for (uint32_t j = 0; j + 1 < jobs.size(); j += 2)
      if (const Residence* r = placed(j))
        for (Lane& lane = devices_[r->place].lanes[which]; uint32_t k : {j, j + 1}) {
          add(lane, k, jobs[k], config);
          if (k == j + 1) refer(lane, jobs[j], jobs[k]);
        }
    for (uint32_t j = 0; j + 1 < jobs.size(); j += 2) {
      if (placed(j)) continue;
      Device& d = *std::min_element(devices_.begin(), devices_.end(), [&](const Device& a, const Device& b) {
        return a.lanes[which].load < b.lanes[which].load;
      });
      for (uint32_t k : {j, j + 1}) add(d.lanes[which], k, jobs[k], config);
      refer(d.lanes[which], jobs[j], jobs[j + 1]);
    }
    for (Device& d : devices_)
      if (Lane& lane = d.lanes[which]; lane.device_counts) {
        lane.items = item_room(lane, lane.searched_jobs);
        const double guess = lane.last_items_per_job * lane.searched_jobs;
        lane.launch_items = guess > 0 ? std::min<uint32_t>(lane.items, uint32_t(guess) + 1) : lane.items;
      }
  }

  // Room for a full batch's items before the device counts them: as many a
  // searched job as the most its lane's batches have held so far (a guess
  // of kFirstItemsPerJob before any), and half again, but never more than
  // all its sources' items (a bound). A batch that outgrows it runs again
  // (rerun_outgrown).
  static uint32_t item_room(const Lane& lane, double jobs) {
    constexpr double kFirstItemsPerJob = 64;
    const double per_job = lane.most_items_per_job > 0 ? lane.most_items_per_job : kFirstItemsPerJob;
    const double guess = 1.5 * per_job * jobs + 64;
    const uint64_t room = std::min<double>(guess, double(lane.item_bound));
    if (room > std::numeric_limits<uint32_t>::max()) throw Error("a device batch holds at most 2^32 - 1 items");
    return uint32_t(room);
  }

  // A job's items: its tracked rays, or the items (origins and edges) of
  // its near leaves. Their count is also the rays it is expected to cast,
  // by which jobs are spread over the devices. Where the device counts a
  // full job's items, its count here is 0 and its source's item count (a
  // bound) goes to the lane's room and load.
  void add(Lane& lane, uint32_t j, const RayJob& job, const Config& config) {
    rtcd_device_job dj{};
    dj.params = make_trace_params(job, *shapes_[job.source], *shapes_[job.target], config);
    const bool searched = lane.device_counts && !job.overlap.empty();
    const size_t items = job.overlap.empty() || lane.device_counts ? 0
                         : job.iterative                            ? job.tracked.size()
                                                                    : mark_near_items(lane, job, dj);
    if (searched) {
      const size_t bound = data_.table[job.source].source_count;
      ++lane.searched_jobs;
      lane.item_bound += bound;
      lane.load += bound;
      lane.unknown_jobs += !(job.residence && job.residence->placed);
    }
    dj.source = job.source;
    dj.target = job.target;
    dj.first_item = lane.items;
    dj.item_count = rtcd_uint(items);
    if (!job.iterative) {
      dj.first_tracked = 0;
    } else if (resident(job)) {
      dj.first_tracked = job.residence->first;
    } else {
      dj.first_tracked = lane.upload_base + rtcd_uint(lane.host_tracked.size());
      if (items > 0) {
        for (const RayOutcome& r : job.tracked) {
          if (r.vertex == kPlaceholder) throw Error("a tracked ray to upload was never recovered");
          lane.host_tracked.push_back({r.vertex, r.triangle, r.entry});
        }
      }
    }
    lane.batch_jobs.push_back(j);
    lane.host_jobs.push_back(dj);
    lane.host_first_items.push_back(lane.items);
    if (runtime_->place_on_device) {
      rtcd_job_setup setup = job_setup(job, config);
      setup.first_item = dj.first_item;
      setup.item_count = dj.item_count;
      setup.first_tracked = dj.first_tracked;
      setup.first_near = dj.first_near;
      add_direction(lane, job, setup);
    } else {
      lane.host_frames.push_back(make_frame(job));
    }
    lane.items += rtcd_uint(items);
    lane.load += items;
    if (job.residence && job.residence->placed) {
      lane.known_reports += job.residence->reports;
    } else {
      lane.unknown_items += items;
    }
  }

  // A job's setup into its pair's: the first of a lane's two jobs of a
  // pair (assign adds them one after the other) opens it, the second adds
  // its side. Either must be what the device makes of the pair's
  // (rtcd_direction_setup), limits derived from the motion included.
  void add_direction(Lane& lane, const RayJob& job, const rtcd_job_setup& s) const {
    const uint32_t d = (lane.batch_jobs.size() - 1) % 2;
    const rtcd_uint first = s.flags & RTCD_JOB_ITERATIVE ? s.first_tracked : s.first_near;
    const rtcd_uint edges = s.flags & RTCD_JOB_EDGES ? RTCD_PAIR_EDGES(d) : 0u;
    if (d == 0 && lane.device_counts) {  // what the device makes of what is sent
      const rtcd_uint motion = job.motion_measured ? RTCD_PAIR_MOTION : 0u;
      lane.host_full.push_back({{s.source_body, s.target_body}, (s.flags & RTCD_JOB_ITERATIVE) | edges | motion});
      lane.host_setups.push_back(rtcd_setup_of_full(lane.host_full.back()));
    } else if (d == 0) {
      const rtcd_uint motion = job.motion_measured ? RTCD_PAIR_MOTION : 0u;
      lane.host_setups.push_back({{s.source_body, s.target_body}, (s.flags & RTCD_JOB_ITERATIVE) | edges | motion,
                                  s.moved, {s.item_count, 0}, {first, 0}});
    } else if (lane.device_counts) {
      lane.host_full.back().flags |= edges;
      lane.host_setups.back().flags |= edges;
    } else {
      rtcd_pair_setup& p = lane.host_setups.back();
      p.flags |= edges;
      p.item_count[1] = s.item_count;
      p.first[1] = first;
    }
    const rtcd_pair_setup& p = lane.host_setups.back();
    const rtcd_uint shape_0 = body_shapes_.at(p.bodies[0]), shape_1 = body_shapes_.at(p.bodies[1]);
    const rtcd_uint pair_first_item = d == 0 ? s.first_item : s.first_item - p.item_count[0];
    const rtcd_shape_scale &scale_0 = data_.scales[shape_0], &scale_1 = data_.scales[shape_1];
    if (d == 0) {  // the pair's motion, as the device derives it, once
      lane.pair_motion = p.flags & RTCD_PAIR_MOTION ? rtcd_bodies_motion(p.bodies[0], p.bodies[1], last_poses_.data(),
                                                                         poses_.data(), scale_0.radius, scale_1.radius)
                                                    : 0.0;
      lane.motions = lane.motions || (p.flags & RTCD_PAIR_MOTION) != 0;
    }
    const double motion = lane.pair_motion;
    const rtcd_job_setup made = rtcd_direction_setup(&p, d, pair_first_item, motion, config_flags(config_),
                                                     &limit_settings_, shape_0, shape_1, &scale_0, &scale_1);
    if (job.motion != motion || std::memcmp(&made, &s, sizeof(s)) != 0)
      throw Error("a pair's setup does not make its job " + std::to_string(lane.batch_jobs.back()) +
                  " (jobs 2i and 2i + 1 must be one pair's two directions, their limits derived from its motion"
                  " between the last step's poses and this step's)");
  }

  // A walking pair's reference (rtcd_pair_ref), once its two jobs are in:
  // to its row of last step's pair table where both directions walk, whole,
  // the rays they kept in one row on this lane's device last step; to its
  // setup sent after the references otherwise.
  void refer(Lane& lane, const RayJob& a, const RayJob& b) const {
    if (!runtime_->place_on_device || !a.iterative) return;
    const rtcd_pair_setup& p = lane.host_setups.back();
    const auto whole = [&](const RayJob& job) {
      return resident(job) && &devices_[job.residence->place].lanes[kWalkedLane] == &lane &&
             job.residence->slot == a.residence->slot && job.tracked.size() == job.residence->count;
    };
    if (whole(a) && whole(b) && a.residence->slot != Residence::kNoRecord) {
      lane.host_refs.push_back(rtcd_pair_ref_of(a.residence->slot, p.flags | RTCD_PAIR_RESIDENT, p.moved));
    } else {
      lane.host_refs.push_back(rtcd_pair_ref_of(lane.setups_sent++, p.flags, p.moved));
    }
  }

  // A full job's items near its overlap box (visit_near_items), where the
  // host places the rays: appended to the batch's as bits (rtcd_near_item);
  // returns how many.
  size_t mark_near_items(Lane& lane, const RayJob& job, rtcd_device_job& dj) const {
    const RaySources& rs = shapes_[job.source]->sources();
    dj.first_near = rtcd_uint(lane.host_near.size());
    lane.host_near.resize(lane.host_near.size() + rtcd_near_words(rs.item_count()), 0);
    rtcd_uint* bits = lane.host_near.data() + dj.first_near;
    size_t items = 0;
    visit_near_items(make_frame(job), rs, shapes_[job.target]->distance_bound(), edge_reach(dj.params),
                     [&](uint32_t v) {
                       bits[v / 32] |= rtcd_uint(1) << (v % 32);
                       ++items;
                     });
    return items;
  }

  // The host's placement, for devices without fp64: the same rtcd_place_item.
  void place_on_host(Lane& lane) {
    lane.host_rays.clear();
    for (uint32_t l = 0; l < lane.host_jobs.size(); ++l) {
      const rtcd_device_job& job = lane.host_jobs[l];
      const RaySources& rs = shapes_[job.source]->sources();
      // Tracked rays, or the near items (mark_near_items).
      const uint32_t count = job.params.iterative || job.item_count == 0 ? job.item_count : rs.item_count();
      for (uint32_t k = 0; k < count; ++k) {
        rtcd_candidate c{k, -1, -1, l, {}, {}};
        if (!job.params.iterative && !rtcd_near_item(lane.host_near.data() + job.first_near, k)) continue;
        if (job.params.iterative) {
          const rtcd_tracked& r = lane.host_tracked[job.first_tracked + k];
          c.vertex = r.vertex;
          c.start = r.triangle;
          c.entry = r.entry;
        }
        const Eigen::Vector3f o = rs.item_origin(c.vertex), dir = rs.item_direction(c.vertex);
        if (rtcd_place_item(&lane.host_frames[l], &job.params, c.vertex, rtcd_v3(o.x(), o.y(), o.z()),
                            rtcd_v3(dir.x(), dir.y(), dir.z()), &c.origin, &c.direction)) {
          lane.host_rays.push_back(c);
          ++lane.host_counts[l];
        }
      }
    }
  }

  // Each job's first ray from the counts, and after the last, the total
  // (rtcd_offsets on the host).
  static void first_rays(Lane& lane) {
    lane.host_first_rays.resize(lane.host_counts.size() + 1);
    uint32_t n = 0;
    for (size_t l = 0; l < lane.host_counts.size(); ++l) {
      lane.host_first_rays[l] = n;
      n += lane.host_counts[l];
    }
    lane.host_first_rays.back() = n;
    lane.ray_count = n;
  }

  // A fixed work-group size, the global size rounded up to it (kernels
  // ignore the excess): drivers such as PoCL compile a kernel again for
  // every new work-group size they would pick themselves.
  // `after`: events of other queues it waits for.
  static void launch(Device& d, cl::Kernel& k, size_t n, const std::vector<cl::Event>* after = nullptr) {
    const size_t group = d.group_size;
    d.queue.enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange((n + group - 1) / group * group), cl::NDRange(group),
                                 after, timed(d, true));
    ++d.work.launches;
  }

  // One work-group: the job scans (rtcd_offsets, rtcd_total), whose
  // work-items share the jobs among them.
  static void launch_group(Device& d, cl::Kernel& k) { launch(d, k, d.group_size); }

  // `args` as a kernel's arguments from index `first` on; returns the next index.
  template <class... Args>
  static cl_uint set_args(cl::Kernel& k, cl_uint first, const Args&... args) {
    (k.setArg(first++, args), ...);
    return first;
  }

  // The arguments both trace kernels open with: the jobs, then the shape
  // data from the table to the BVH's triangle lists. Returns the next
  // argument's index.
  static cl_uint bind_jobs_and_shapes(Device& d, Lane& lane, cl::Kernel& k) {
    k.setArg(0, lane.jobs.buffer);
    for (size_t i = 0; i < kTracedShapeBuffers; ++i) k.setArg(cl_uint(1 + i), d.shapes[i]);
    return cl_uint(1 + kTracedShapeBuffers);
  }

  // rtcd_trace over at most `rays` rays, in strides of `launch_size`.
  void enqueue_trace(Device& d, Lane& lane, uint32_t rays, uint32_t launch_size) {
    reserve(lane.outcomes, rays * sizeof(rtcd_outcome));
    cl::Kernel& k = d.trace;
    const cl_uint next = bind_jobs_and_shapes(d, lane, k);
    k.setArg(next, lane.rays.buffer);
    k.setArg(next + 1, lane.first_rays.buffer);
    k.setArg(next + 2, rtcd_uint(lane.host_jobs.size()));
    k.setArg(next + 3, lane.outcomes.buffer);
    launch(d, k, launch_size);
  }

  // After the trace, on the device: each job's outcomes counted
  // (rtcd_tallies, rtcd_total), its kept rays written one job after
  // another past kept_base, where the residences record them, once the
  // recovery reads of two steps ago have read that buffer, and its reports
  // laid out (rtcd_lay_out). Then the reads: the counters, the summaries,
  // the reports up to a bound guessed from the last step, and, where the
  // host placed the rays, the kept rays. Room is made for `count` rays, an
  // upper bound when they are not counted yet.
  void settle(Device& d, Lane& lane, const GrowingBuffer& firsts, uint32_t count) {
    const auto jobs_count = rtcd_uint(lane.host_jobs.size());
    GrowingBuffer& kept = d.kept[step_ % 2];
    uint32_t& used = d.kept_used[step_ % 2];
    lane.kept_base = used;
    reserve_keeping<rtcd_tracked>(d, kept, size_t(used) + count, used);
    used += count;
    reserve(lane.flags, 1);  // bound unread by the compacted layout
    reserve(lane.tallies, jobs_count * sizeof(rtcd_tally));
    reserve(lane.laid_out, 2 * (size_t(jobs_count) + 1) * sizeof(rtcd_uint));
    reserve(lane.summaries, jobs_count * sizeof(rtcd_job_summary));
    reserve(lane.total, sizeof(rtcd_tally));
    reserve(lane.reports, count * sizeof(rtcd_report));
    const rtcd_uint in_grid = grid(lane);
    const cl::Buffer& counts = in_grid ? firsts.buffer : lane.counts.buffer;  // the grid reads item counts
    // rtcd_tallies and rtcd_lay_out open with the arguments that find each
    // job's outcomes (RTCD_JOB_RAYS).
    const auto bind_job_rays = [&](cl::Kernel& k) {
      return set_args(k, 0, lane.jobs.buffer, jobs_count, in_grid, firsts.buffer, counts, lane.flags.buffer,
                      lane.outcomes.buffer);
    };
    cl::Kernel& c = d.tallies;
    set_args(c, bind_job_rays(c), lane.tallies.buffer);
    launch(d, c, jobs_count);
    cl::Kernel& t = d.total;
    set_args(t, 0, lane.tallies.buffer, jobs_count, lane.laid_out.buffer, lane.summaries.buffer, lane.total.buffer);
    launch_group(d, t);
    cl::Kernel& l = d.lay_out;
    reserve(lane.setups, 1);  // unread where the host made the setups
    reserve(d.pair_table[step_ % 2], 1);
    set_args(l, bind_job_rays(l), lane.laid_out.buffer, lane.kept_base, kept.buffer, lane.reports.buffer,
             lane.setups.buffer, lane.slot_base, d.pair_table[step_ % 2].buffer);
    launch(d, l, jobs_count, &d.recovering[step_ % 2]);
    lane.host_total.resize(1);
    lane.host_summaries.resize(jobs_count);
    lane.host_reports.resize(count);
    lane.report_bound = std::min<uint32_t>(count, uint32_t(1.25 * expected_reports(d, lane)) + 64);
    read(d, lane.total, lane.host_total);
    read(d, lane.summaries, lane.host_summaries);
    if (lane.device_counts) {
      lane.host_found.resize(1);
      read(d, lane.items_found, lane.host_found);
    }
    if (!runtime_->place_on_device) {
      lane.host_kept.resize(count);
      read(d, kept, lane.kept_base, lane.host_kept, 0, count);
    }
    read(d, lane.reports, 0, lane.host_reports, 0, lane.report_bound, &lane.outcomes_read);
  }

  // How a batch's rays are laid out (DeviceLayout). Compacted: a prefix sum
  // over each job's candidate flags, then one work-item per candidate (the
  // counts and outcomes read back together). Grid (Figure 2.6): one
  // work-item per item, candidate or not, traced in place (every item's
  // outcome read back). By mode: grid for iterative batches, whose items
  // are last step's rays and nearly all candidates; compacted for full
  // ones, where most vertices are not (docs/results/opencl.md measures
  // both). The pipeline never mixes modes in a batch.
  bool grid(const Lane& lane) const {
    return runtime_->place_on_device &&
           (layout_ == DeviceLayout::grid ||
            (layout_ == DeviceLayout::by_mode && lane.host_jobs.front().params.iterative));
  }

  // The grid layout: every item placed and traced in place by one kernel
  // (the non-candidates return at once, unflagged).
  void trace_in_place(Device& d, Lane& lane) {
    reserve(lane.outcomes, lane.items * sizeof(rtcd_outcome));
    cl::Kernel& k = d.trace_items;
    const cl_uint next = bind_jobs_and_shapes(d, lane, k);
    set_args(k, next, lane.item_jobs.buffer, lane.frames.buffer, lane.items_found.buffer, rtcd_uint(lane.items),
             d.shapes[kOrigins], d.shapes[kDirections], lane.vertices.buffer, d.kept[(step_ + 1) % 2].buffer,
             lane.flags.buffer, lane.outcomes.buffer);
    launch(d, k, lane.launch_items);
    settle(d, lane, lane.first_items, lane.items);
  }

  // Phase 1, on the device: the jobs' frames made from the step's poses
  // (uploaded once a step) and a full batch's items listed; for the
  // compacted layout, candidates placed, flagged, counted per job and laid
  // out (the grid layout places them as it traces them).
  void place_on_device(Device& d, Lane& lane) {
    const auto jobs_count = rtcd_uint(lane.host_jobs.size());
    if (d.poses_written != step_) {
      std::swap(d.poses, d.before);
      d.before_written = std::exchange(d.poses_written, step_);
      write(d, d.poses, poses_);
    }
    if (lane.motions && d.before_written != step_ - 1) {  // the device had no job last step
      write(d, d.before, last_poses_);
      d.before_written = step_ - 1;
    }
    reserve(d.before, 1);  // unread without motions
    if (d.body_shapes_written != body_shapes_.size()) {  // bodies were added
      write(d, d.body_shapes, body_shapes_);
      d.body_shapes_written = body_shapes_.size();
    }
    send_pairs(d, lane);
    reserve(lane.jobs, jobs_count * sizeof(rtcd_device_job));
    reserve(lane.frames, jobs_count * sizeof(rtcd_frame));
    // Tracked rays that were not kept here come from the host's mirror,
    // after the kept ones the walks read.
    GrowingBuffer& tracked = d.kept[(step_ + 1) % 2];
    reserve_keeping<rtcd_tracked>(d, tracked, size_t(lane.upload_base) + lane.host_tracked.size(), lane.upload_base);
    write_at(d, tracked, lane.host_tracked, lane.upload_base);
    d.kept_used[(step_ + 1) % 2] = lane.upload_base + rtcd_uint(lane.host_tracked.size());
    reserve(lane.flags, lane.items);
    reserve(lane.vertices, lane.items * sizeof(rtcd_uint));
    reserve(lane.item_jobs, lane.items * sizeof(rtcd_uint));
    // Room for each full job's near items as bits (rtcd_near_find).
    const rtcd_uint near_stride = lane.device_counts ? rtcd_near_words(data_.most_items) : 0;
    reserve(lane.near, size_t(jobs_count) * near_stride * sizeof(rtcd_uint));
    cl::Kernel& p = d.prepare;
    const rtcd_limit_settings& l = limit_settings_;
    set_args(p, 0, lane.setups.buffer, jobs_count, config_flags(config_), l.displacement_threshold,
             l.distance_extension, l.max_walk_steps, l.set, d.shapes[kTable], d.shapes[kTraits], d.shapes[kBounds],
             d.shapes[kScales], d.shapes[kSourceNodes], d.shapes[kSourceOrder], d.shapes[kLeafItems],
             d.shapes[kGrids], d.shapes[kGridValues], lane.near.buffer, near_stride,
             d.poses.buffer, d.before.buffer, d.body_shapes.buffer, lane.jobs.buffer, lane.first_items.buffer,
             lane.frames.buffer, lane.items_found.buffer, rtcd_uint(lane.items), lane.vertices.buffer,
             lane.item_jobs.buffer);
    launch(d, p, jobs_count);
    if (grid(lane)) return;
    reserve(lane.staging, lane.items * sizeof(rtcd_candidate));
    set_args(d.select, 0, lane.jobs.buffer, lane.item_jobs.buffer, lane.frames.buffer, lane.items_found.buffer,
             rtcd_uint(lane.items), d.shapes[kTable], d.shapes[kOrigins], d.shapes[kDirections], lane.vertices.buffer,
             tracked.buffer, lane.flags.buffer, lane.staging.buffer);
    launch(d, d.select, lane.launch_items);
    reserve(lane.slots, lane.items * sizeof(rtcd_uint));
    reserve(lane.counts, jobs_count * sizeof(rtcd_uint));
    cl::Kernel& c = d.count;
    c.setArg(0, lane.jobs.buffer);
    c.setArg(1, jobs_count);
    c.setArg(2, lane.flags.buffer);
    c.setArg(3, lane.slots.buffer);
    c.setArg(4, lane.counts.buffer);
    launch(d, c, jobs_count);
    reserve(lane.first_rays, (size_t(jobs_count) + 1) * sizeof(rtcd_uint));
    set_args(d.offsets, 0, lane.counts.buffer, jobs_count, lane.first_rays.buffer);
    launch_group(d, d.offsets);
  }

  // The batch's pairs up (a full batch's bodies and flags, or a walking
  // batch's references and the setups they name) and their setups made on
  // the device, with a walking batch's item list (rtcd_pair_list); rows for
  // them in the step's pair table.
  void send_pairs(Device& d, Lane& lane) {
    const auto jobs_count = rtcd_uint(lane.host_jobs.size());
    if (lane.device_counts) {
      write(d, lane.list, lane.host_full);
    } else {
      const auto words = [](const auto& v) { return std::as_bytes(std::span(v)).size() / sizeof(rtcd_uint); };
      lane.host_list.resize(words(lane.host_refs) + size_t(lane.setups_sent) * RTCD_PAIR_SETUP_WORDS);
      std::memcpy(lane.host_list.data(), lane.host_refs.data(), lane.host_refs.size() * sizeof(rtcd_pair_ref));
      rtcd_uint* sent = lane.host_list.data() + words(lane.host_refs);
      for (size_t p = 0; p < lane.host_refs.size(); ++p) {
        const rtcd_uint slot_flags = lane.host_refs[p].slot_flags;
        if (slot_flags & RTCD_PAIR_RESIDENT) continue;
        std::memcpy(sent + size_t(slot_flags >> RTCD_PAIR_FLAG_BITS) * RTCD_PAIR_SETUP_WORDS, &lane.host_setups[p],
                    sizeof(rtcd_pair_setup));
      }
      write(d, lane.list, lane.host_list);
    }
    reserve(lane.setups, lane.host_setups.size() * sizeof(rtcd_pair_setup));
    reserve(lane.first_items, (size_t(jobs_count) + 1) * sizeof(rtcd_uint));
    reserve(d.pair_table[(step_ + 1) % 2], 1);  // unread by a full batch
    reserve(lane.items_found, sizeof(rtcd_uint));
    set_args(d.pair_list, 0, lane.list.buffer, jobs_count, rtcd_uint(lane.host_refs.size()),
             d.pair_table[(step_ + 1) % 2].buffer, lane.setups.buffer, lane.first_items.buffer,
             lane.items_found.buffer);
    launch_group(d, d.pair_list);
    uint32_t& rows = d.rows_used[step_ % 2];
    if (lane.host_setups.size() > RTCD_PAIR_MAX_SLOT - rows)
      throw Error("a device holds at most " + std::to_string(RTCD_PAIR_MAX_SLOT) + " pairs a step");
    lane.slot_base = rows;
    reserve_keeping<rtcd_pair_setup>(d, d.pair_table[step_ % 2], size_t(rows) + lane.host_setups.size(), rows);
    rows += uint32_t(lane.host_setups.size());
  }

  // The compacted layout on the device: candidates scattered and traced
  // with no count known on the host (the launch covers every item).
  void trace_compacted(Device& d, Lane& lane) {
    reserve(lane.rays, lane.items * sizeof(rtcd_candidate));
    set_args(d.scatter, 0, lane.item_jobs.buffer, lane.first_rays.buffer, lane.items_found.buffer,
             rtcd_uint(lane.items), lane.flags.buffer, lane.slots.buffer, lane.staging.buffer, lane.rays.buffer);
    launch(d, d.scatter, lane.launch_items);
    enqueue_trace(d, lane, lane.items, lane.launch_items);
    settle(d, lane, lane.first_rays, lane.items);
  }

  // A batch's reports, guessed before they are counted: each job's last
  // where it ran before (a pair's reports change little from step to step,
  // walked or traced again), the last full batch's reports per item for
  // the items of new pairs.
  static double expected_reports(const Device& d, const Lane& lane) {
    const double unknown = double(lane.unknown_items) + lane.most_items_per_job * double(lane.unknown_jobs);
    return lane.known_reports + d.lanes[kFullLane].reports_per_item * unknown;
  }

  // After the wait: each job's first kept ray from the summaries, and the
  // reports the guessed bound left unread, enqueued behind `last`; returns
  // whether there were any.
  bool count_results(Device& d, Lane& lane, cl::Event& last) {
    const size_t jobs = lane.host_summaries.size();
    const rtcd_tally& total = lane.host_total[0];
    lane.host_first_kept.resize(jobs + 1);
    uint64_t kept = 0;
    for (size_t l = 0; l < jobs; ++l) {
      const rtcd_job_summary& s = lane.host_summaries[l];
      // The device's counts place what the host reads: they must fit.
      if (s.kept_origins > s.kept || s.kept > (lane.device_counts ? lane.found : lane.host_jobs[l].item_count))
        throw Error("a device returned inconsistent counts for job " + std::to_string(l));
      lane.host_first_kept[l] = rtcd_uint(kept);
      kept += s.kept;
    }
    const uint64_t rays = total.candidates + total.edges_tested, reports = total.contacts + total.predictive;
    if (kept != total.kept || rays > lane.found || reports > kept)
      throw Error("a device returned inconsistent counts for a batch");
    lane.host_first_kept[jobs] = rtcd_uint(kept);
    lane.ray_count = uint32_t(rays);
    lane.report_count = uint32_t(reports);
    lane.reports_per_item = lane.found > 0 ? double(reports) / lane.found : 0.0;
    if (reports <= lane.report_bound) return false;
    read(d, lane.reports, 0, lane.host_reports, lane.report_bound, reports - lane.report_bound, &last);
    return true;
  }

  // After the wait, the device's count of a full batch's items: past the
  // room made for them, the batch runs again with room for them all (and
  // the host waits again); its first run's kept rays and pair rows are left
  // unused. Then the most items a searched job that the lane has seen.
  void rerun_outgrown(Device& d, Lane& lane) {
    if (!lane.pending || !lane.device_counts) return;
    const uint32_t found = lane.host_found[0];
    if (found > lane.item_bound) throw Error("a device found more items than its jobs' sources hold");
    if (lane.searched_jobs > 0)
      lane.last_items_per_job = double(found) / lane.searched_jobs;
    lane.most_items_per_job = std::max(lane.most_items_per_job, lane.last_items_per_job);
    if (found > lane.items) {
      lane.items = lane.launch_items = found;
      enqueue(d, lane, false);
      wait(d, lane.outcomes_read);
      if (lane.host_found[0] != found) throw Error("a device found other items when it ran a batch again");
    }
    lane.found = found;
  }

  // One device's share of a batch, enqueued and flushed; nothing waits.
  // Each device is driven from its own host thread: some drivers (PoCL's
  // `basic`) run a device's commands in the thread that flushes or waits
  // on it.
  void enqueue(Device& d, Lane& lane, bool inject_mid_step) {
    lane.host_counts.assign(lane.host_jobs.size(), 0);
    lane.ray_count = 0;
    lane.found = lane.items;  // where the device counts, known after the wait
    if (!lane.device_counts) lane.launch_items = lane.items;
    if (lane.items == 0) return;
    upload_shapes(d);
    if (!runtime_->place_on_device) {
      place_on_host(lane);
    } else {
      place_on_device(d, lane);
    }
    if (inject_mid_step) throw cl::Error(CL_OUT_OF_RESOURCES, "clEnqueueNDRangeKernel (injected fault)");
    if (grid(lane)) {
      trace_in_place(d, lane);
    } else if (runtime_->place_on_device) {
      trace_compacted(d, lane);
    } else {  // the host placed and counted the rays
      first_rays(lane);
      if (lane.ray_count == 0) return;
      write(d, lane.jobs, lane.host_jobs);
      write(d, lane.first_rays, lane.host_first_rays);
      write(d, lane.counts, lane.host_counts);
      write(d, lane.rays, lane.host_rays);
      enqueue_trace(d, lane, lane.ray_count, lane.ray_count);
      settle(d, lane, lane.first_rays, lane.ray_count);
    }
    d.queue.flush();
    lane.pending = true;
  }

  // Both lanes' results on the host: one wait, for the last read enqueued
  // (an in-order queue has finished everything before it), and a second
  // only when a guessed bound fell short.
  void finish(Device& d) {
    Lane* last = nullptr;
    for (Lane& lane : d.lanes)
      if (lane.pending) last = &lane;
    if (!last) return;
    wait(d, last->outcomes_read);
    rerun_outgrown(d, d.lanes[kFullLane]);
    cl::Event rest;
    bool more = false;
    for (Lane& lane : d.lanes)
      if (lane.pending) more = count_results(d, lane, rest) || more;
    if (more) wait(d, rest);
    for (Lane& lane : d.lanes) {
      lane.ran = lane.pending;
      lane.pending = false;
    }
    read_for_recovery(d);
  }

  // The walk starts of the rays the device kept this step, read on the
  // recovery queue into the host's copy of `kept`, place for place;
  // nothing waits for them (fill_walk_starts may). Where the host placed
  // the rays it has them already.
  void read_for_recovery(Device& d) {
    if (!runtime_->place_on_device) return;
    const size_t parity = step_ % 2;
    wait_recovered(d, parity, false);  // two steps ago, into the same host memory: long done
    d.recovering[parity].clear();
    std::vector<rtcd_tracked>& starts = d.recovered[parity];
    starts.resize(d.kept_used[parity]);
    for (const Lane& lane : d.lanes) {
      if (!lane.ran || lane.ray_count == 0) continue;
      const size_t count = lane.host_first_kept.back();
      if (count == 0) continue;
      d.recovery.enqueueReadBuffer(d.kept[parity].buffer, CL_FALSE, lane.kept_base * sizeof(rtcd_tracked),
                                   count * sizeof(rtcd_tracked), starts.data() + lane.kept_base, nullptr,
                                   &d.recovering[parity].emplace_back());
      d.work.bytes_recovery += count * sizeof(rtcd_tracked);
      ++d.work.reads;
    }
    d.recovery.flush();
  }

  // The step's full batch is enqueued and left to run; the walked one
  // (RayExecutor::execute) is enqueued behind it, and each device's thread
  // waits once for both and hands their outcomes to their slots (disjoint
  // ones: the step keeps job order, and no copy waits for the slowest
  // device).
  void run(RayBatch& batch) {
    const size_t which = batch.iterative ? kWalkedLane : kFullLane;
    assign(which, batch.jobs, config_);
    // An injected mid-step fault strikes after the batch's first kernels
    // were enqueued: the second batch with work, or the first walked one
    // behind a full batch with work.
    bool work = false, full_work = false;
    for (const Device& d : devices_) {
      work = work || d.lanes[which].items > 0;
      full_work = full_work || (full_ && d.lanes[kFullLane].items > 0);
    }
    batches_ += work;
    const bool inject_mid_step = (fault_ == OpenClFault::mid_step && batches_ == 2) ||
                                 (fault_ == OpenClFault::behind_full && batch.iterative && work && full_work);
    if (!batch.iterative) full_ = &batch;
    auto run_device = [&](uint32_t i) {
      Device& d = devices_[i];
      enqueue(d, d.lanes[which], inject_mid_step);
      if (!batch.iterative) return;
      finish(d);
      collect(d);
      if (full_) deliver(i, d.lanes[kFullLane], *full_);
      deliver(i, d.lanes[kWalkedLane], batch);
    };
    if (devices_.size() == 1) {
      run_device(0);
    } else {
      tbb::parallel_for(
          tbb::blocked_range<size_t>(0, devices_.size(), 1),
          [&](const tbb::blocked_range<size_t>& r) {
            for (size_t i = r.begin(); i != r.end(); ++i) run_device(uint32_t(i));
          },
          tbb::simple_partitioner());
    }
    if (!batch.iterative) return;
    // The devices' counters, summed on this thread.
    for (const Device& d : devices_) {
      if (full_) add_counted(d.lanes[kFullLane], *full_);
      add_counted(d.lanes[kWalkedLane], batch);
    }
    full_ = nullptr;
  }

  static void add_counted(const Lane& lane, RayBatch& batch) {
    if (!lane.ran) return;
    RayTally counted;
    counted += lane.host_total[0];
    batch.counted += counted;
  }

  // Device i's jobs of a batch: their kept outcomes built in their slots
  // (the reports whole, in their places; the others placeholders, or
  // whole where the host placed the rays), their records counted, and
  // where their kept rays are, for the next step.
  void deliver(uint32_t i, const Lane& lane, RayBatch& batch) {
    Device& d = devices_[i];
    if (lane.ray_count > 0) d.work.rays += lane.ray_count;
    // The reports come in job order, each naming its job.
    const rtcd_report* report = lane.host_reports.data();
    const rtcd_report* const reports_end = report + (lane.ray_count > 0 ? lane.report_count : 0);
    for (size_t l = 0; l < lane.batch_jobs.size(); ++l) {
      const uint32_t j = lane.batch_jobs[l];
      const RayJob& job = batch.jobs[j];
      const rtcd_device_job& dj = lane.host_jobs[l];
      d.work.jobs += lane.device_counts ? !job.overlap.empty() : dj.item_count > 0;
      std::vector<RayOutcome>& out = batch.outcomes[j];
      RayTally& tally = batch.tallies[j];
      tally = {};
      tally.place = int32_t(i);
      out.clear();
      const uint64_t kept_step = runtime_->place_on_device ? step_ : 0;
      if (lane.ray_count == 0) {  // nothing ran there, and nothing is kept
        if (job.residence) *job.residence = {kept_step, i, 0, 0, true, 0};
        continue;
      }
      const uint32_t first = lane.host_first_kept[l];
      const rtcd_job_summary& s = lane.host_summaries[l];
      const int target_kind = data_.table[dj.target].kind;
      const auto edge_kind = rtcd_uchar(rtcd_item_kind(target_kind, &dj.params, dj.params.first_edge));
      // Built one by one, not by resize: that would write every outcome
      // twice, zeros first (the vector keeps its capacity from step to step).
      out.reserve(s.kept);
      for (uint32_t k = 0; k < s.kept; ++k) {
        RayOutcome o;  // rtcd_outcome_init sets every field
        if (runtime_->place_on_device) {
          rtcd_outcome_init(&o, kPlaceholder);
        } else {
          const rtcd_tracked& r = lane.host_kept[first + k];
          rtcd_outcome_init(&o, r.vertex);
          o.triangle = r.triangle;
          o.entry = r.entry;
        }
        o.kind = RTCD_RAY_WATCHED;
        o.edge = k < s.kept_origins ? rtcd_uchar(RTCD_ITEM_ORIGIN) : edge_kind;
        out.push_back(o);
      }
      for (; report != reports_end && report->job == l; ++report) {
        if (report->place >= s.kept)
          throw Error("a device returned a report out of place for job " + std::to_string(l));
        out[report->place] = report->outcome;
        tally.contacts += report->outcome.kind == RTCD_RAY_PENETRATING;
        tally.predictive += report->outcome.kind == RTCD_RAY_PREDICTIVE;
      }
      if (job.residence) {
        const auto made = uint32_t(tally.contacts + tally.predictive);
        const uint32_t slot = lane.slot_base == RTCD_NO_SLOT ? Residence::kNoRecord : lane.slot_base + uint32_t(l / 2);
        *job.residence = {kept_step, i, lane.kept_base + first, s.kept, true, made, slot};
      }
    }
    if (report != reports_end) throw Error("a device returned a report out of its job's order");
  }

  std::string name_;
  std::shared_ptr<const Runtime> runtime_;
  bool bvh_;
  DeviceLayout layout_;
  OpenClFault fault_;
  CpuFallback fallback_;
  std::string fault_message_;  // set once the devices are given up
  std::vector<std::shared_ptr<const Shape>> shapes_;
  std::vector<ShapeScale> scales_;
  ShapeData data_;
  std::vector<Device> devices_;
  std::unique_ptr<RayExecutor> cpu_;
  Config config_;
  rtcd_limit_settings limit_settings_{};
  uint64_t batches_ = 0;  // batches with rays
  uint64_t step_ = 0;     // begin_step calls
  // Every body's pose, the step's (begin_step) and the last step's, kept
  // for a device that was not sent them then.
  std::vector<rtcd_pose> poses_, last_poses_;
  std::vector<rtcd_uint> body_shapes_;  // by BodyId (add_body)
  bool on_cpu_ = false;   // some batch of this step ran on the CPU fallback
  RayBatch* full_ = nullptr;  // the step's full batch, enqueued and not finished
  std::mutex recovering_;     // one waiter for a device's recovery reads
  std::vector<std::vector<RayOutcome>> taken_over_;  // walks the CPU took over, by job
};
}  // namespace
}  // namespace rtcd::opencl

namespace rtcd {

std::unique_ptr<NarrowPhase> make_opencl_narrow_phase(const BackendOptions& options, const Config& config,
                                                      CpuFallback fallback) {
  using namespace opencl;
  config.validate();
  options.validate();
  const Selection selection = Selection::of(options);
  const OpenClFault fault = requested_opencl_fault();
  const std::string name = options.name();
  std::shared_ptr<const Runtime> runtime;
  std::string setup_fault;
  std::vector<std::string> devices;
  try {
    runtime = acquire_runtime(selection, fault);
    devices = runtime->descriptions;
  } catch (const NameError&) {
    throw;
  } catch (const Error& e) {
    setup_fault = e.what();
  } catch (const cl::Error& e) {
    setup_fault = describe(e);
  }
  if (!setup_fault.empty()) devices = {"cpu fallback (" + fallback.name + "): " + setup_fault};
  auto executor = std::make_unique<OpenClExecutor>(name, std::move(runtime), setup_fault, selection.bvh, options.layout,
                                                   fault, std::move(fallback));
  return make_pipeline_narrow_phase(name, std::move(devices), std::move(executor), config, options.threads);
}

std::vector<BackendInfo> opencl_backend_infos() {
  using namespace opencl;
  // Platforms do not come and go within a process.
  static const std::vector<BackendInfo> infos = [] {
    std::vector<BackendInfo> list;
    try {
      const Found found = find_devices(Selection{});
      std::string devices;
      for (size_t i = 0; i < found.devices.size(); ++i)
        devices += (i ? "; " : "") + describe(found.platform, found.devices[i], i);
      list.push_back({"opencl", true, "BVH on " + devices});
      list.push_back({"opencl-basic", true, "every ray against every triangle on " + devices});
    } catch (const std::exception& e) {
      list.push_back({"opencl", false, e.what()});
      list.push_back({"opencl-basic", false, e.what()});
    }
    return list;
  }();
  return infos;
}

}  // namespace rtcd
