// Kernels of kernels.cl alone, on the device, against the host.
//
// The job scans: rtcd_offsets (each
// job's first ray and the total) and rtcd_total (each job's summary and
// first report, the batch's counters summed) run as one work-group whose
// work-items each take a share of the jobs. Their answers against the
// host's sums for job counts around multiples of the group's width, where
// a share's bounds or its prefix would slip. The replays reach a few of
// these counts only by chance.
//
// The frames: rtcd_prepare makes each job's frame from its bodies' poses
// by the function the pipeline's place runs on the host; the two must be
// the same bits, or a device would place rays the CPU does not.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "opencl/device_types.h"
#include "opencl/runtime.hpp"

namespace rtcd::test {
namespace {

using opencl::Runtime;

constexpr size_t kGroupSize = 64;  // the executor's
const size_t kJobCounts[] = {1, 2, 63, 64, 65, 127, 128, 129, 1000, 4095, 4096, 4097};

std::shared_ptr<const Runtime> runtime() {
  return opencl::acquire_runtime(opencl::Selection{}, OpenClFault::none);
}

// Scan kernel `name` over `jobs` jobs as the executor launches it: one
// work-group; its arguments the first buffer, the job count, the others.
void run_scan(const Runtime& rt, const char* name, size_t jobs, const std::vector<cl::Buffer>& buffers) {
  cl::Kernel k(rt.program, name);
  k.setArg(0, buffers[0]);
  k.setArg(1, rtcd_uint(jobs));
  for (size_t i = 1; i < buffers.size(); ++i) k.setArg(cl_uint(i + 1), buffers[i]);
  const cl::Device& device = rt.devices.front();
  const size_t group = std::min(kGroupSize, k.getWorkGroupInfo<CL_KERNEL_WORK_GROUP_SIZE>(device));
  cl::CommandQueue queue(rt.context, device);
  queue.enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(group), cl::NDRange(group));
  queue.finish();
}

template <class T>
cl::Buffer buffer_of(const Runtime& rt, std::vector<T>& v) {
  return cl::Buffer(rt.context, CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR, v.size() * sizeof(T), v.data());
}

template <class T>
void read_back(const Runtime& rt, const cl::Buffer& b, std::vector<T>& v) {
  cl::CommandQueue(rt.context, rt.devices.front()).enqueueReadBuffer(b, CL_TRUE, 0, v.size() * sizeof(T), v.data());
}

TEST(OpenClScans, OffsetsAreTheHostsPrefixSumAroundGroupMultiples) {
  const auto rt = runtime();
  std::mt19937 g(11);
  std::uniform_int_distribution<rtcd_uint> count(0, 40);
  for (const size_t jobs : kJobCounts) {
    SCOPED_TRACE(std::to_string(jobs) + " jobs");
    std::vector<rtcd_uint> counts(jobs), first_rays(jobs + 1, 0xdeadbeef);
    for (rtcd_uint& c : counts) c = count(g);
    const cl::Buffer firsts_buffer = buffer_of(*rt, first_rays);
    run_scan(*rt, "rtcd_offsets", jobs, {buffer_of(*rt, counts), firsts_buffer});
    read_back(*rt, firsts_buffer, first_rays);
    rtcd_uint sum = 0;
    for (size_t j = 0; j < jobs; ++j) {
      ASSERT_EQ(first_rays[j], sum) << "job " << j;
      sum += counts[j];
    }
    EXPECT_EQ(first_rays[jobs], sum);
  }
}

TEST(OpenClScans, TotalsAreTheHostsSumsAroundGroupMultiples) {
  const auto rt = runtime();
  std::mt19937 g(12);
  std::uniform_int_distribution<rtcd_uint> small(0, 9);
  for (const size_t jobs : kJobCounts) {
    SCOPED_TRACE(std::to_string(jobs) + " jobs");
    std::vector<rtcd_tally> tallies(jobs);
    rtcd_tally expected;
    rtcd_tally_clear(&expected);
    for (rtcd_tally& t : tallies) {
      rtcd_tally_clear(&t);
      t.contacts = small(g);
      t.predictive = small(g);
      t.kept = t.contacts + t.predictive + small(g);
      t.kept_origins = t.kept / 2;
      t.candidates = t.kept + small(g);
      t.edges_tested = small(g);
      t.walk_steps = small(g);
      t.walk_endings[RTCD_LINE_STATUS_COUNT - 1] = small(g);
      rtcd_tally_add(&expected, &t);
    }
    std::vector<rtcd_uint> first_reports(jobs + 1, 0xdeadbeef);
    std::vector<rtcd_job_summary> summaries(jobs);
    std::vector<rtcd_tally> total(1);
    const cl::Buffer firsts_buffer = buffer_of(*rt, first_reports), summaries_buffer = buffer_of(*rt, summaries);
    const cl::Buffer total_buffer = buffer_of(*rt, total);
    run_scan(*rt, "rtcd_total", jobs, {buffer_of(*rt, tallies), firsts_buffer, summaries_buffer, total_buffer});
    read_back(*rt, firsts_buffer, first_reports);
    read_back(*rt, summaries_buffer, summaries);
    read_back(*rt, total_buffer, total);
    rtcd_uint reports = 0;
    for (size_t j = 0; j < jobs; ++j) {
      const rtcd_tally& t = tallies[j];
      const rtcd_job_summary& s = summaries[j];
      ASSERT_EQ(first_reports[j], reports) << "job " << j;
      ASSERT_EQ(s.rays, t.candidates + t.edges_tested) << "job " << j;
      ASSERT_EQ(s.kept, t.kept) << "job " << j;
      ASSERT_EQ(s.kept_origins, t.kept_origins) << "job " << j;
      ASSERT_EQ(s.contacts + s.predictive, t.contacts + t.predictive) << "job " << j;
      reports += rtcd_uint(t.contacts + t.predictive);
    }
    EXPECT_EQ(first_reports[jobs], reports);
    EXPECT_EQ(total[0].contacts, expected.contacts);
    EXPECT_EQ(total[0].kept, expected.kept);
    EXPECT_EQ(total[0].kept_origins, expected.kept_origins);
    EXPECT_EQ(total[0].candidates, expected.candidates);
    EXPECT_EQ(total[0].walk_steps, expected.walk_steps);
    EXPECT_EQ(total[0].walk_endings[RTCD_LINE_STATUS_COUNT - 1], expected.walk_endings[RTCD_LINE_STATUS_COUNT - 1]);
  }
}

// Random poses far from the origin and random boxes: the frames
// rtcd_prepare makes are the host's rtcd_relative_frame bit for bit, and
// that is the transform target⁻¹ ∘ source (Eigen's, to rounding).
TEST(OpenClFrames, PrepareMakesTheHostsFramesBitForBit) {
  const auto rt = runtime();
  if (!rt->place_on_device) GTEST_FAIL() << "the device lacks fp64: the host makes the frames there";
  std::mt19937 g(13);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), far(-1e4, 1e4), size(0.01, 3.0);
  constexpr size_t kBodies = 300, kShapes = 7, kJobs = 1000;
  std::vector<rtcd_pose> poses(kBodies);
  std::vector<Eigen::Quaterniond> orientations(kBodies);
  for (size_t b = 0; b < kBodies; ++b) {
    orientations[b] = Eigen::Quaterniond(unit(g), unit(g), unit(g), unit(g)).normalized();
    const Eigen::Quaterniond& q = orientations[b];
    poses[b] = {{q.w(), q.x(), q.y(), q.z()}, {far(g), far(g), far(g)}};
  }
  std::vector<rtcd_box> bounds(kShapes);
  for (rtcd_box& box : bounds)
    for (int i = 0; i < 3; ++i) {
      box.lo[i] = unit(g) - size(g);
      box.hi[i] = box.lo[i] + 2 * size(g);
    }
  std::vector<rtcd_device_job> jobs(kJobs);
  std::vector<rtcd_frame_job> frame_jobs(kJobs);
  std::uniform_int_distribution<rtcd_uint> body(0, kBodies - 1), shape(0, kShapes - 1);
  for (size_t j = 0; j < kJobs; ++j) {
    jobs[j] = rtcd_device_job{};
    jobs[j].params.iterative = 1;  // nothing to list: the frame alone
    jobs[j].source = shape(g);
    jobs[j].target = shape(g);
    // Neighbours a few units apart (the candidate box not empty), and any two.
    const rtcd_uint source = body(g);
    rtcd_uint target = body(g);
    if (j % 2 == 0) {
      target = (source + 1) % kBodies;
      for (int i = 0; i < 3; ++i) poses[target].position[i] = poses[source].position[i] + unit(g);
    }
    frame_jobs[j] = {source, target, size(g) / 10};
  }
  std::vector<rtcd_device_shape> table(kShapes);
  std::vector<rtcd_uint> unused(1);
  std::vector<rtcd_frame> frames(kJobs);
  cl::Kernel k(rt->program, "rtcd_prepare");
  const cl::Buffer frames_buffer = buffer_of(*rt, frames);
  const cl::Buffer args[] = {buffer_of(*rt, jobs),       buffer_of(*rt, table),  buffer_of(*rt, unused),
                             buffer_of(*rt, unused),     buffer_of(*rt, unused), buffer_of(*rt, frame_jobs),
                             buffer_of(*rt, poses),      buffer_of(*rt, bounds), frames_buffer};
  k.setArg(0, args[0]);
  k.setArg(1, rtcd_uint(kJobs));
  for (cl_uint i = 1; i < 9; ++i) k.setArg(i + 1, args[i]);
  cl::CommandQueue queue(rt->context, rt->devices.front());
  queue.enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange((kJobs + kGroupSize - 1) / kGroupSize * kGroupSize),
                             cl::NDRange(kGroupSize));
  queue.finish();
  read_back(*rt, frames_buffer, frames);
  size_t boxes = 0;
  for (size_t j = 0; j < kJobs; ++j) {
    const rtcd_frame_job& fj = frame_jobs[j];
    rtcd_frame host;
    rtcd_relative_frame(&poses[fj.source_body], &poses[fj.target_body], &bounds[jobs[j].source],
                        &bounds[jobs[j].target], fj.extension, &host);
    ASSERT_EQ(std::memcmp(&host, &frames[j], sizeof(rtcd_frame)), 0) << "job " << j << ": the device's frame differs";
    boxes += host.lo[0] <= host.hi[0] && host.lo[1] <= host.hi[1] && host.lo[2] <= host.hi[2];
    // The transform itself, against Eigen's.
    const rtcd_pose &s = poses[fj.source_body], &t = poses[fj.target_body];
    const Eigen::Quaterniond to_target = orientations[fj.target_body].conjugate() * orientations[fj.source_body];
    const Eigen::Matrix3d rotation = to_target.toRotationMatrix();
    const Eigen::Vector3d translation =
        orientations[fj.target_body].conjugate() * (Eigen::Vector3d(s.position[0], s.position[1], s.position[2]) -
                                                    Eigen::Vector3d(t.position[0], t.position[1], t.position[2]));
    for (int i = 0; i < 3; ++i) {
      ASSERT_NEAR(host.translation[i], translation[i], 1e-9 * (1 + translation.norm())) << "job " << j;
      for (int c = 0; c < 3; ++c) ASSERT_NEAR(host.rotation[3 * i + c], rotation(i, c), 1e-14) << "job " << j;
    }
  }
  EXPECT_GT(boxes, kJobs / 10) << "the neighbours' candidate boxes must be boxes, or the test says little";
}

}  // namespace
}  // namespace rtcd::test
