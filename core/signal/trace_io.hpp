// Reading a time series (time, amplitude) from a laboratory or engine file: CSV/whitespace
// text (columns chosen by index; lines that do not start with a number, such as headers and
// '#' comments, are skipped) or two 1-D datasets of an HDF5 file.
#pragma once
#include <string>

#include "core/signal/trace.hpp"

namespace granular {

Trace read_trace_csv(const std::string& path, int time_column, int amplitude_column);
Trace read_trace_h5(const std::string& path, const std::string& time_dataset,
                    const std::string& amplitude_dataset);
// The `unit` attribute of a dataset of an HDF5 file (every dataset of an engine results.h5
// carries one), or "" where it has none, it is not a single string, or the file or dataset
// cannot be read.
std::string read_dataset_unit(const std::string& path, const std::string& dataset);

}  // namespace granular
