// MPI ranks (see mpi_ranks.hpp).
#include "mpi_ranks.hpp"

#include <cstdlib>
#include <limits>
#include <string>

#include "rtcd/error.hpp"

#ifdef RTCD_WITH_MPI
#include <mpi.h>
#endif

namespace rtcd::cli {
namespace {

// The job's size as the launcher tells it: Open MPI's, MPICH's (Hydra), PMIx's.
int launched_size() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"})
    if (const char* v = std::getenv(name)) return std::atoi(v);
  return 0;
}

#ifdef RTCD_WITH_MPI
class MpiRanks : public app::Ranks {
 public:
  MpiRanks() {
    MPI_Init(nullptr, nullptr);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
  }
  ~MpiRanks() override { MPI_Finalize(); }
  int rank() const override { return rank_; }
  int size() const override { return size_; }

  std::vector<std::string> gather(const std::string& mine) const override {
    if (mine.size() > size_t(std::numeric_limits<int>::max()))
      throw UsageError("rank " + std::to_string(rank_) + "'s share of a run is too large to gather (" +
                       std::to_string(mine.size()) + " bytes): run it as a --campaign");
    int length = int(mine.size());
    std::vector<int> lengths(static_cast<size_t>(size_)), offsets(static_cast<size_t>(size_));
    MPI_Gather(&length, 1, MPI_INT, lengths.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
    std::string all;
    if (reports()) {
      size_t total = size_t(lengths[0]);
      for (int r = 1; r < size_; ++r) {
        if (total > size_t(std::numeric_limits<int>::max()))
          throw UsageError("a run is too large to gather in one piece: run it as a --campaign");
        offsets[size_t(r)] = int(total);
        total += size_t(lengths[size_t(r)]);
      }
      all.resize(total);
    }
    MPI_Gatherv(mine.data(), length, MPI_CHAR, all.data(), lengths.data(), offsets.data(), MPI_CHAR, 0,
                MPI_COMM_WORLD);
    std::vector<std::string> out;
    if (reports())
      for (int r = 0; r < size_; ++r) out.push_back(all.substr(size_t(offsets[size_t(r)]), size_t(lengths[size_t(r)])));
    return out;
  }

  std::string broadcast(const std::string& text) const override {
    unsigned long length = text.size();
    MPI_Bcast(&length, 1, MPI_UNSIGNED_LONG, 0, MPI_COMM_WORLD);
    std::string out = reports() ? text : std::string(length, '\0');
    MPI_Bcast(out.data(), int(length), MPI_CHAR, 0, MPI_COMM_WORLD);
    return out;
  }

  void barrier() const override { MPI_Barrier(MPI_COMM_WORLD); }

 private:
  int rank_ = 0, size_ = 1;
};
#endif

bool initialized = false;

}  // namespace

std::unique_ptr<app::Ranks> mpi_ranks_if_launched() {
  const int size = launched_size();
  if (size <= 0) return nullptr;
#ifdef RTCD_WITH_MPI
  initialized = true;
  return std::make_unique<MpiRanks>();
#else
  if (size > 1)
    throw UsageError("started as one of " + std::to_string(size) +
                     " MPI ranks, but this rtcd was built without MPI (configure with RTCD_WITH_MPI=ON)");
  return nullptr;
#endif
}

void abort_job(int code) {
#ifdef RTCD_WITH_MPI
  if (initialized) MPI_Abort(MPI_COMM_WORLD, code);
#endif
  std::exit(code);
}

}  // namespace rtcd::cli
