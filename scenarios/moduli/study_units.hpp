// The units of a checkpointed study (preparation variants, mixtures) over the ranks of a
// run (core/run/ensemble.hpp). Rank 0 says which units an earlier run finished (its
// checkpoints); the others are dealt round robin in unit order, so a study killed on R ranks
// resumes on any R'. Each finished unit is a part file in <out>/variants/; rank 0 reads
// every part back in unit order at the end, so the outputs do not depend on who ran what.
#pragma once
#include <string>
#include <vector>

namespace granular {

struct StudyDeal {
  std::vector<bool> done;  // finished by an earlier run (rank 0's checkpoints)
  std::vector<int> owner;  // the rank that runs each unit (-1 where done)
  bool mine(size_t unit) const;
};

// Collective. `names`: the part name of each unit. Throws InputError (on rank 0) for a
// checkpoint of other scene parameters.
StudyDeal deal_study_units(const std::string& parts, const std::vector<std::string>& names,
                           const std::string& fingerprint, bool resume);

// Collective: rank 0 gets this rank's files of the units it ran (finished parts and stage
// checkpoints in `parts`) and the `extra` files (saved configurations), for ranks that do
// not share a file system with it.
void collect_study_files(const std::string& parts, const std::vector<std::string>& unit_names,
                         const std::vector<std::string>& extra);

struct ModuliOutputs;

// Collective, over several ranks, after each rank ran its units: collect_study_files, then
// whether any rank `stopped`; on rank 0, when none did, every unit's part read back in unit
// order into `out`. Returns whether the study stopped (on every rank).
bool gather_study_units(const std::string& parts, const std::vector<std::string>& names,
                        const std::vector<std::string>& ran, const std::vector<std::string>& extra,
                        const std::string& fingerprint, bool stopped, ModuliOutputs& out);

}  // namespace granular
