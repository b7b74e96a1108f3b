// The job scans of kernels.cl alone, on the device: rtcd_offsets (each
// job's first ray and the total) and rtcd_total (each job's summary and
// first report, the batch's counters summed) run as one work-group whose
// work-items each take a share of the jobs. Their answers against the
// host's sums for job counts around multiples of the group's width, where
// a share's bounds or its prefix would slip. The replays reach a few of
// these counts only by chance.
#include <gtest/gtest.h>

#include <random>
#include <vector>

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

}  // namespace
}  // namespace rtcd::test
