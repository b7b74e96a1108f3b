// The processes a command runs on: this one alone, or the ranks of an MPI
// job (the CLI's, when started by mpirun). rtcd::app knows this interface
// only, so neither it nor Python links MPI.
#pragma once

#include <string>
#include <vector>

namespace rtcd::app {

class Ranks {
 public:
  virtual ~Ranks() = default;
  virtual int rank() const { return 0; }
  virtual int size() const { return 1; }
  // Every rank's `mine` by rank on rank 0; nothing on the others.
  virtual std::vector<std::string> gather(const std::string& mine) const { return {mine}; }
  // Rank 0's `text` on every rank.
  virtual std::string broadcast(const std::string& text) const { return text; }
  virtual void barrier() const {}
  bool reports() const { return rank() == 0; }
};

// The one process of a command run without mpirun.
const Ranks& one_process();

}  // namespace rtcd::app
