// Numeric matrices from MAT files (MATLAB levels 4, 5 and 7.3) through libmatio, for the PyShoe
// layout of IMU recordings (tools/io/imu_reader.h). Built without libmatio, Open() says so.
#ifndef GROVE_TOOLS_IO_MAT_FILE_H_
#define GROVE_TOOLS_IO_MAT_FILE_H_

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "grove/status.h"

namespace grove::tools {

// A real two-dimensional matrix, column-major as MATLAB stores it.
struct MatMatrix {
  size_t rows = 0;
  size_t columns = 0;
  std::vector<double> values;
  double At(size_t row, size_t column) const { return values[row + column * rows]; }
};

// An open MAT file. Not thread-safe (nor is libmatio's logging, which it silences). Movable.
class MatFile {
 public:
  // NotFound for a missing file; InvalidArgument for a file that is not a MAT file, or when
  // grove was built without libmatio.
  static StatusOr<MatFile> Open(const std::string& path);
  MatFile(MatFile&&) noexcept;
  MatFile& operator=(MatFile&&) noexcept;
  ~MatFile();

  bool Has(const std::string& name) const;
  // The variable `name` as doubles: a real numeric (or logical) matrix of rank 2; any integer
  // or single class is converted. InvalidArgument naming the file and variable otherwise.
  StatusOr<MatMatrix> ReadMatrix(const std::string& name) const;

  class Handle;

 private:
  MatFile(std::string path, std::unique_ptr<Handle> handle);
  std::string path_;
  std::unique_ptr<Handle> handle_;
};

// Writes `matrices` (name, matrix) as a MAT file of level 5: the test fixtures and the
// examples' PyShoe-layout files. InvalidArgument when built without libmatio.
Status WriteMatFile(const std::string& path,
                    const std::vector<std::pair<std::string, MatMatrix>>& matrices);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_IO_MAT_FILE_H_
