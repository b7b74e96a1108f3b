// The ranks of the MPI job this process was started in by mpirun (or
// another launcher that sets the job's size), or nothing when it was not.
#pragma once

#include <memory>

#include "rtcd/app/ranks.hpp"

namespace rtcd::cli {

// Initializes MPI for the process's lifetime when a launcher started it;
// nullptr otherwise. Throws UsageError when launched as one of several
// ranks by a build without MPI.
std::unique_ptr<app::Ranks> mpi_ranks_if_launched();

// Ends every rank of the job with `code` (a rank that fails would leave the
// others waiting for it).
[[noreturn]] void abort_job(int code);

}  // namespace rtcd::cli
