// Kernels of kernels.cl alone, on the device, against the host.
//
// The job scans: rtcd_offsets (each
// job's first ray and the total), rtcd_pair_list (each pair's setup, each
// job's first item) and rtcd_total (each job's summary and
// first report, the batch's counters summed) run as one work-group whose
// work-items each take a share of the jobs. Their answers against the
// host's sums for job counts around multiples of the group's width, where
// a share's bounds or its prefix would slip. The replays reach a few of
// these counts only by chance.
//
// The jobs: rtcd_prepare makes each job's parameters from its setup and its
// frame from its bodies' poses by the functions the host runs (the CPU
// executor's make_trace_params, the pipeline's place); the two must be the
// same bits, or a device would place and trace rays the CPU does not.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "opencl/device_types.h"
#include "opencl/runtime.hpp"
#include "rtcd/criterion.hpp"

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

// rtcd_pair_list makes the pairs' setups from what the host sent: a full
// batch's setups as they are; a walking batch's references, each to its
// row of last step's pair table (its bodies and kept rays, with the
// reference's flags and motion) or to a setup sent after them. Then its
// item list: job 2p (direction 0 of pair p) starts where the pairs before
// it end, job 2p + 1 after direction 0's items.
TEST(OpenClScans, PairListsMakeTheSetupsAndTheHostsPrefixSumAroundGroupMultiples) {
  const auto rt = runtime();
  if (!rt->place_on_device) GTEST_FAIL() << "the device lacks fp64: the host lays out the items there";
  std::mt19937 g(15);
  std::uniform_int_distribution<rtcd_uint> count(0, 40), word(0, 1u << 20);
  const auto random_setup = [&] {
    return rtcd_pair_setup{{word(g), word(g)}, word(g) % 16, float(word(g)), {count(g), count(g)}, {word(g), word(g)}};
  };
  std::vector<rtcd_pair_setup> table(50);
  for (rtcd_pair_setup& row : table) row = random_setup();
  for (const bool walking : {false, true}) {
    for (const size_t pairs : kJobCounts) {
      SCOPED_TRACE(std::string(walking ? "walking, " : "full, ") + std::to_string(pairs) + " pairs");
      std::vector<rtcd_pair_setup> setups(pairs), sent;
      std::vector<rtcd_pair_ref> refs;
      std::vector<rtcd_full_pair> full;  // a full batch sends bodies and flags; its items are found later
      for (rtcd_pair_setup& p : setups) {
        p = random_setup();
        if (!walking) {
          full.push_back({{p.bodies[0], p.bodies[1]}, p.flags});
          p = rtcd_setup_of_full(full.back());
          continue;
        }
        const rtcd_uint row = word(g) % (2 * table.size());
        if (row < table.size()) {  // resident: the row's but for flags and motion
          const rtcd_pair_setup flags_and_motion = p;
          p = table[row];
          p.flags = flags_and_motion.flags;
          p.moved = flags_and_motion.moved;
          refs.push_back(rtcd_pair_ref_of(row, p.flags | RTCD_PAIR_RESIDENT, p.moved));
        } else {
          refs.push_back(rtcd_pair_ref_of(rtcd_uint(sent.size()), p.flags, p.moved));
          sent.push_back(p);
        }
      }
      std::vector<rtcd_uint> list;  // the references' words, then the sent setups'
      const auto append = [&list](const auto& records) {
        const auto* words = reinterpret_cast<const rtcd_uint*>(records.data());
        list.insert(list.end(), words, words + records.size() * sizeof(records[0]) / sizeof(rtcd_uint));
      };
      append(refs);
      if (walking) append(sent);
      else append(full);
      list.push_back(0);  // no empty buffer
      std::vector<rtcd_pair_setup> made(pairs);
      std::vector<rtcd_uint> first_items(2 * pairs + 1, 0xdeadbeef), items(1, 0xdeadbeef);
      const cl::Buffer made_buffer = buffer_of(*rt, made), firsts_buffer = buffer_of(*rt, first_items);
      const cl::Buffer items_buffer = buffer_of(*rt, items);
      const cl::Buffer list_buffer = buffer_of(*rt, list), table_buffer = buffer_of(*rt, table);
      cl::Kernel k(rt->program, "rtcd_pair_list");
      k.setArg(0, list_buffer);
      k.setArg(1, rtcd_uint(2 * pairs));
      k.setArg(2, rtcd_uint(refs.size()));
      k.setArg(3, table_buffer);
      k.setArg(4, made_buffer);
      k.setArg(5, firsts_buffer);
      k.setArg(6, items_buffer);
      const cl::Device& device = rt->devices.front();
      const size_t group = std::min(kGroupSize, k.getWorkGroupInfo<CL_KERNEL_WORK_GROUP_SIZE>(device));
      cl::CommandQueue queue(rt->context, device);
      queue.enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(group), cl::NDRange(group));
      queue.finish();
      read_back(*rt, made_buffer, made);
      read_back(*rt, firsts_buffer, first_items);
      read_back(*rt, items_buffer, items);
      rtcd_uint sum = 0;
      for (size_t p = 0; p < pairs; ++p) {
        ASSERT_EQ(std::memcmp(&made[p], &setups[p], sizeof(rtcd_pair_setup)), 0) << "pair " << p;
        ASSERT_EQ(first_items[2 * p], sum) << "pair " << p;
        ASSERT_EQ(first_items[2 * p + 1], sum + setups[p].item_count[0]) << "pair " << p;
        sum += setups[p].item_count[0] + setups[p].item_count[1];
      }
      EXPECT_EQ(first_items[2 * pairs], sum);
      EXPECT_EQ(items[0], sum) << "the batch's item count";
      if (!walking) {
        EXPECT_EQ(sum, 0u);
      }
    }
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
    // rtcd_total writes each job's first kept ray, then its first report.
    std::vector<rtcd_uint> firsts(2 * (jobs + 1), 0xdeadbeef);
    std::vector<rtcd_job_summary> summaries(jobs);
    std::vector<rtcd_tally> total(1);
    const cl::Buffer firsts_buffer = buffer_of(*rt, firsts), summaries_buffer = buffer_of(*rt, summaries);
    const cl::Buffer total_buffer = buffer_of(*rt, total);
    run_scan(*rt, "rtcd_total", jobs, {buffer_of(*rt, tallies), firsts_buffer, summaries_buffer, total_buffer});
    read_back(*rt, firsts_buffer, firsts);
    read_back(*rt, summaries_buffer, summaries);
    read_back(*rt, total_buffer, total);
    const rtcd_uint* first_kept = firsts.data();
    const rtcd_uint* first_reports = firsts.data() + jobs + 1;
    rtcd_uint kept = 0, reports = 0;
    for (size_t j = 0; j < jobs; ++j) {
      const rtcd_tally& t = tallies[j];
      const rtcd_job_summary& s = summaries[j];
      ASSERT_EQ(first_kept[j], kept) << "job " << j;
      ASSERT_EQ(first_reports[j], reports) << "job " << j;
      ASSERT_EQ(s.kept, t.kept) << "job " << j;
      ASSERT_EQ(s.kept_origins, t.kept_origins) << "job " << j;
      kept += rtcd_uint(t.kept);
      reports += rtcd_uint(t.contacts + t.predictive);
    }
    EXPECT_EQ(first_kept[jobs], kept);
    EXPECT_EQ(first_reports[jobs], reports);
    EXPECT_EQ(total[0].contacts, expected.contacts);
    EXPECT_EQ(total[0].kept, expected.kept);
    EXPECT_EQ(total[0].kept_origins, expected.kept_origins);
    EXPECT_EQ(total[0].candidates, expected.candidates);
    EXPECT_EQ(total[0].walk_steps, expected.walk_steps);
    EXPECT_EQ(total[0].walk_endings[RTCD_LINE_STATUS_COUNT - 1], expected.walk_endings[RTCD_LINE_STATUS_COUNT - 1]);
  }
}

// Random pair setups, shapes, scales, poses far from the origin and the
// last step's near them, configurations and limit settings: the jobs (with
// their first items) and frames rtcd_prepare makes are those the host's
// rtcd_bodies_motion, rtcd_derive_limits, rtcd_make_params and
// rtcd_relative_frame make from each direction's setup, bit for bit; the
// frame is the transform target⁻¹ ∘ source and the motion equation 2.1
// (Eigen's, to rounding).
TEST(OpenClFrames, PrepareMakesTheHostsJobsAndFramesBitForBit) {
  const auto rt = runtime();
  if (!rt->place_on_device) GTEST_FAIL() << "the device lacks fp64: the host makes the frames there";
  std::mt19937 g(13);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), far(-1e4, 1e4), size(0.01, 3.0);
  std::uniform_int_distribution<rtcd_uint> word(0, 1000), bit(0, 1);
  constexpr size_t kBodies = 300, kShapes = 7, kJobs = 1000;
  std::vector<rtcd_pose> poses(kBodies), before(kBodies);
  std::vector<Eigen::Quaterniond> orientations(kBodies);
  for (size_t b = 0; b < kBodies; ++b) {
    orientations[b] = Eigen::Quaterniond(unit(g), unit(g), unit(g), unit(g)).normalized();
    const Eigen::Quaterniond& q = orientations[b];
    poses[b] = {{q.w(), q.x(), q.y(), q.z()}, {far(g), far(g), far(g)}};
    // The last step's: turned and moved a little, or (every third) as now.
    const Eigen::Quaterniond turned =
        b % 3 == 0 ? q : (q * Eigen::Quaterniond(Eigen::AngleAxisd(0.1 * unit(g), Eigen::Vector3d::UnitX())));
    before[b] = {{turned.w(), turned.x(), turned.y(), turned.z()}, {poses[b].position[0] + 0.1 * unit(g),
                 poses[b].position[1], poses[b].position[2] + (b % 3 == 0 ? 0.0 : 0.01 * unit(g))}};
  }
  std::vector<rtcd_box> bounds(kShapes);
  std::vector<rtcd_shape_traits> traits(kShapes);
  for (size_t i = 0; i < kShapes; ++i) {
    for (int k = 0; k < 3; ++k) {
      bounds[i].lo[k] = unit(g) - size(g);
      bounds[i].hi[k] = bounds[i].lo[k] + 2 * size(g);
    }
    const rtcd_int kind = rtcd_int(i % 4);  // mesh, sphere, box, half-space
    traits[i] = {kind, rtcd_int(bit(g)), word(g), kind == RTCD_TARGET_SPHERE ? float(size(g)) : 0.0f};
  }
  // Scales as measure_scale gives them: a half-space has no radius, and
  // only meshes an edge length.
  std::vector<rtcd_shape_scale> scales(kShapes);
  for (size_t i = 0; i < kShapes; ++i) {
    const bool half_space = traits[i].kind == RTCD_TARGET_HALFSPACE, mesh = traits[i].kind == RTCD_TARGET_MESH;
    scales[i] = {half_space ? 0.0 : size(g), half_space ? INFINITY : size(g) / 3, mesh ? size(g) / 50 : INFINITY,
                 mesh ? word(g) : 0u, 0u};
  }
  std::vector<rtcd_pair_setup> pairs(kJobs / 2);
  std::uniform_int_distribution<rtcd_uint> body(0, kBodies - 1), shape(0, kShapes - 1);
  std::vector<rtcd_uint> body_shapes(kBodies);
  for (rtcd_uint& s : body_shapes) s = shape(g);
  for (size_t i = 0; i < pairs.size(); ++i) {
    rtcd_pair_setup& p = pairs[i];
    p.moved = float(size(g) / 30);
    p.bodies[0] = body(g);
    p.bodies[1] = body(g);
    // Neighbours a few units apart (the candidate box not empty), and any two.
    if (i % 2 == 0) {
      p.bodies[1] = (p.bodies[0] + 1) % kBodies;
      for (int k = 0; k < 3; ++k) poses[p.bodies[1]].position[k] = poses[p.bodies[0]].position[k] + unit(g);
    }
    // Walks: nothing to list, the jobs and frames alone.
    p.flags = RTCD_JOB_ITERATIVE | (bit(g) ? RTCD_PAIR_EDGES(0) : 0u) | (bit(g) ? RTCD_PAIR_EDGES(1) : 0u) |
              (i % 5 == 0 ? 0u : RTCD_PAIR_MOTION);
    p.item_count[0] = word(g);
    p.item_count[1] = word(g);
    p.first[0] = word(g);
    p.first[1] = word(g);
  }
  std::vector<rtcd_device_shape> table(kShapes);
  // Each pair's items after the last's, as rtcd_offsets lays them out.
  std::vector<rtcd_uint> unused(1), first_items(kJobs);
  for (size_t j = 0, n = 0; j < kJobs; n += pairs[j / 2].item_count[j % 2], ++j) first_items[j] = rtcd_uint(n);
  std::vector<rtcd_device_job> jobs(kJobs);
  std::vector<rtcd_frame> frames(kJobs);
  std::vector<rtcd_job_setup> setups(kJobs);
  // Buffers outlive the kernel's use: setting an argument does not retain one.
  const cl::Buffer setups_buffer = buffer_of(*rt, pairs), jobs_buffer = buffer_of(*rt, jobs),
                   firsts_buffer = buffer_of(*rt, first_items), frames_buffer = buffer_of(*rt, frames);
  cl::Kernel k(rt->program, "rtcd_prepare");
  cl::CommandQueue queue(rt->context, rt->devices.front());
  size_t boxes = 0, moving = 0;
  // Configurations and limit settings: every limit derived, every one set, and mixes.
  const std::pair<rtcd_uint, rtcd_limit_settings> cases[] = {
      {0u, {0.0, 0.0, 0u, 0u}},
      {63u, {0.01, 0.1, 40u, RTCD_LIMIT_THRESHOLD | RTCD_LIMIT_EXTENSION | RTCD_LIMIT_WALK}},
      {RTCD_CONFIG_PREDICTIVE | RTCD_CONFIG_EDGES | RTCD_CONFIG_AUTOMATIC, {0.0, 0.05, 0u, RTCD_LIMIT_EXTENSION}},
      {RTCD_CONFIG_VERIFY, {0.02, 0.0, 100u, RTCD_LIMIT_THRESHOLD | RTCD_LIMIT_WALK}}};
  for (const auto& [config, settings] : cases) {
    SCOPED_TRACE("configuration " + std::to_string(config) + ", limits set " + std::to_string(settings.set));
    // Job j is direction j % 2 of pair j / 2: the first body's rays at the
    // second, then the other way, its items after the first's.
    for (size_t j = 0; j < kJobs; ++j) {
      const rtcd_pair_setup& p = pairs[j / 2];
      const rtcd_uint d = j % 2, shapes[2] = {body_shapes[p.bodies[0]], body_shapes[p.bodies[1]]};
      const double motion = p.flags & RTCD_PAIR_MOTION
                                ? rtcd_bodies_motion(p.bodies[0], p.bodies[1], before.data(), poses.data(),
                                                     scales[shapes[0]].radius, scales[shapes[1]].radius)
                                : 0.0;
      if (p.flags & RTCD_PAIR_MOTION) {
        // Equation 2.1 by Eigen: the relative pose of the lower id's body in
        // the higher id's (the other way when it has no radius), before and now.
        const rtcd_uint low = std::min(p.bodies[0], p.bodies[1]), high = std::max(p.bodies[0], p.bodies[1]);
        const double low_radius = scales[body_shapes[low]].radius, high_radius = scales[body_shapes[high]].radius;
        const auto relative = [&](const rtcd_pose& l, const rtcd_pose& h) {
          const rtcd::Pose from = rtcd::from_kernel(low_radius > 0.0 ? l : h);
          const rtcd::Pose to = rtcd::from_kernel(low_radius > 0.0 ? h : l);
          return to.inverse() * from;
        };
        const rtcd::Pose was = relative(before[low], before[high]), is = relative(poses[low], poses[high]);
        const double angle =
            2.0 * std::atan2((was.orientation.conjugate() * is.orientation).vec().norm(),
                             std::abs((was.orientation.conjugate() * is.orientation).w()));
        const double expected =
            (was.position - is.position).norm() + angle * std::max(low_radius, high_radius);
        ASSERT_NEAR(motion, expected, 1e-9 * (1.0 + expected)) << "pair " << j / 2;
        moving += motion > 0.0;
      }
      rtcd_job_setup& s = setups[j] = rtcd_direction_setup(&p, d, first_items[j - d], motion, config, &settings,
                                                           shapes[0], shapes[1], &scales[shapes[0]],
                                                           &scales[shapes[1]]);
      ASSERT_EQ(s.source_body, p.bodies[d]);
      ASSERT_EQ(s.target_body, p.bodies[1 - d]);
      ASSERT_EQ(s.source, shapes[d]);
      ASSERT_EQ(s.target, shapes[1 - d]);
      ASSERT_EQ(s.first_item, first_items[j]);
      ASSERT_EQ(s.first_tracked, p.first[d]);
      ASSERT_EQ((s.flags & RTCD_JOB_EDGES) != 0, (p.flags & RTCD_PAIR_EDGES(d)) != 0);
      const rtcd_pair_limits l = rtcd_derive_limits(&settings, &scales[shapes[1]], &scales[shapes[0]], motion);
      ASSERT_EQ(s.extension, l.distance_extension) << "the rules are symmetric";
      ASSERT_EQ(s.reach, config & RTCD_CONFIG_AUTOMATIC ? l.displacement_threshold : l.distance_extension);
      ASSERT_EQ(s.max_walk_steps, l.max_walk_steps);
    }
    k.setArg(0, setups_buffer);
    k.setArg(1, rtcd_uint(kJobs));
    k.setArg(2, config);
    k.setArg(3, settings.displacement_threshold);
    k.setArg(4, settings.distance_extension);
    k.setArg(5, settings.max_walk_steps);
    k.setArg(6, settings.set);
    // Walks: the full jobs' source trees, distance bounds, near items and item list unread.
    const rtcd_uint item_total = first_items.back() + pairs.back().item_count[1];
    std::vector<rtcd_uint> item_jobs(item_total, 0xdeadbeef), items{item_total};
    const cl::Buffer item_jobs_buffer = buffer_of(*rt, item_jobs);
    const cl::Buffer args[] = {buffer_of(*rt, table),  buffer_of(*rt, traits), buffer_of(*rt, bounds),
                               buffer_of(*rt, scales), buffer_of(*rt, unused), buffer_of(*rt, unused),
                               buffer_of(*rt, unused), buffer_of(*rt, unused), buffer_of(*rt, unused),
                               buffer_of(*rt, unused)};
    cl_uint next = 7;
    for (const cl::Buffer& b : args) k.setArg(next++, b);
    k.setArg(next++, rtcd_uint(0));  // near leaves' stride
    const cl::Buffer rest[] = {buffer_of(*rt, poses), buffer_of(*rt, before), buffer_of(*rt, body_shapes),
                               jobs_buffer,           firsts_buffer,          frames_buffer,
                               buffer_of(*rt, items)};
    for (const cl::Buffer& b : rest) k.setArg(next++, b);
    k.setArg(next++, item_total);  // room
    const cl::Buffer vertices_buffer = buffer_of(*rt, unused);
    k.setArg(next++, vertices_buffer);
    k.setArg(next++, item_jobs_buffer);
    queue.enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange((kJobs + kGroupSize - 1) / kGroupSize * kGroupSize),
                               cl::NDRange(kGroupSize));
    queue.finish();
    read_back(*rt, jobs_buffer, jobs);
    read_back(*rt, frames_buffer, frames);
    read_back(*rt, item_jobs_buffer, item_jobs);
    for (size_t j = 0; j < kJobs; ++j)
      for (rtcd_uint n = 0; n < pairs[j / 2].item_count[j % 2]; ++n)
        ASSERT_EQ(item_jobs[first_items[j] + n], j) << "item " << n << " of job " << j;
    for (size_t j = 0; j < kJobs; ++j) {
      const rtcd_job_setup& s = setups[j];
      const rtcd_device_job job =
          rtcd_device_job_of(config, &s, &traits[s.source], &traits[s.target], &bounds[s.target]);
      ASSERT_EQ(std::memcmp(&job, &jobs[j], sizeof(job)), 0) << "job " << j << ": the device's job differs";
      rtcd_frame host;
      rtcd_relative_frame(&poses[s.source_body], &poses[s.target_body], &bounds[s.source], &bounds[s.target],
                          s.extension, &host);
      ASSERT_EQ(std::memcmp(&host, &frames[j], sizeof(rtcd_frame)), 0) << "job " << j << ": the device's frame differs";
      boxes += host.lo[0] <= host.hi[0] && host.lo[1] <= host.hi[1] && host.lo[2] <= host.hi[2];
      // The transform itself, against Eigen's.
      const rtcd_pose &from = poses[s.source_body], &to = poses[s.target_body];
      const Eigen::Quaterniond inverse = orientations[s.target_body].conjugate();
      const Eigen::Matrix3d rotation = (inverse * orientations[s.source_body]).toRotationMatrix();
      const Eigen::Vector3d translation =
          inverse * (Eigen::Vector3d(from.position[0], from.position[1], from.position[2]) -
                     Eigen::Vector3d(to.position[0], to.position[1], to.position[2]));
      for (int i = 0; i < 3; ++i) {
        ASSERT_NEAR(host.translation[i], translation[i], 1e-9 * (1 + translation.norm())) << "job " << j;
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(host.rotation[3 * i + c], rotation(i, c), 1e-14) << "job " << j;
      }
    }
  }
  EXPECT_GT(boxes, 4 * kJobs / 10) << "the neighbours' candidate boxes must be boxes, or the test says little";
  EXPECT_GT(moving, kJobs / 2) << "most pairs must move, or the motions' test says little";
}

}  // namespace
}  // namespace rtcd::test
