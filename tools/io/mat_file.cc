#include "tools/io/mat_file.h"

#include <fmt/format.h>
#include <sys/stat.h>

#include <cstdint>
#include <utility>

#ifdef GROVE_HAVE_MATIO
#include <matio.h>
#endif

namespace grove::tools {

#ifdef GROVE_HAVE_MATIO

namespace {

// libmatio prints its errors; grove reports its own.
void Quiet(int, char*) {}

void SilenceMatio() {
  static const bool silenced = [] {
    Mat_LogInitFunc("grove", Quiet);
    return true;
  }();
  (void)silenced;
}

template <typename T>
void Convert(const void* data, size_t n, std::vector<double>* out) {
  const T* p = static_cast<const T*>(data);
  out->resize(n);
  for (size_t i = 0; i < n; ++i) (*out)[i] = static_cast<double>(p[i]);
}

}  // namespace

class MatFile::Handle {
 public:
  explicit Handle(mat_t* mat) : mat_(mat) {}
  ~Handle() { Mat_Close(mat_); }
  mat_t* get() const { return mat_; }

 private:
  mat_t* mat_;
};

StatusOr<MatFile> MatFile::Open(const std::string& path) {
  SilenceMatio();
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) return NotFoundError(fmt::format("{}: no such file", path));
  if (!S_ISREG(st.st_mode))
    return InvalidArgumentError(fmt::format("{}: not a regular file", path));
  mat_t* mat = Mat_Open(path.c_str(), MAT_ACC_RDONLY);
  if (mat == nullptr) {
    return InvalidArgumentError(fmt::format("{}: not a MAT file (MATLAB level 4, 5 or 7.3)", path));
  }
  return MatFile(path, std::make_unique<Handle>(mat));
}

bool MatFile::Has(const std::string& name) const {
  matvar_t* info = Mat_VarReadInfo(handle_->get(), name.c_str());
  if (info == nullptr) return false;
  Mat_VarFree(info);
  return true;
}

StatusOr<MatMatrix> MatFile::ReadMatrix(const std::string& name) const {
  matvar_t* var = Mat_VarRead(handle_->get(), name.c_str());
  if (var == nullptr) {
    return InvalidArgumentError(fmt::format("{}: no variable {}", path_, name));
  }
  std::unique_ptr<matvar_t, void (*)(matvar_t*)> owned(var, Mat_VarFree);
  if (var->rank != 2 || var->isComplex || var->data == nullptr) {
    return InvalidArgumentError(
        fmt::format("{}: variable {}: expected a real two-dimensional matrix (rank {}{})", path_,
                    name, var->rank, var->isComplex ? ", complex" : ""));
  }
  MatMatrix m;
  m.rows = var->dims[0];
  m.columns = var->dims[1];
  const size_t n = m.rows * m.columns;
  switch (var->class_type) {
    case MAT_C_DOUBLE:
      Convert<double>(var->data, n, &m.values);
      break;
    case MAT_C_SINGLE:
      Convert<float>(var->data, n, &m.values);
      break;
    case MAT_C_INT8:
      Convert<int8_t>(var->data, n, &m.values);
      break;
    case MAT_C_UINT8:
      Convert<uint8_t>(var->data, n, &m.values);
      break;
    case MAT_C_INT16:
      Convert<int16_t>(var->data, n, &m.values);
      break;
    case MAT_C_UINT16:
      Convert<uint16_t>(var->data, n, &m.values);
      break;
    case MAT_C_INT32:
      Convert<int32_t>(var->data, n, &m.values);
      break;
    case MAT_C_UINT32:
      Convert<uint32_t>(var->data, n, &m.values);
      break;
    case MAT_C_INT64:
      Convert<int64_t>(var->data, n, &m.values);
      break;
    case MAT_C_UINT64:
      Convert<uint64_t>(var->data, n, &m.values);
      break;
    default:
      return InvalidArgumentError(
          fmt::format("{}: variable {}: expected a numeric matrix (MATLAB class {})", path_, name,
                      static_cast<int>(var->class_type)));
  }
  return m;
}

Status WriteMatFile(const std::string& path,
                    const std::vector<std::pair<std::string, MatMatrix>>& matrices) {
  SilenceMatio();
  mat_t* mat = Mat_CreateVer(path.c_str(), nullptr, MAT_FT_MAT5);
  if (mat == nullptr) return IoError(fmt::format("{}: cannot create", path));
  Status status;
  for (const auto& [name, m] : matrices) {
    size_t dims[2] = {m.rows, m.columns};
    std::vector<double> data = m.values;
    matvar_t* var = Mat_VarCreate(name.c_str(), MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, data.data(),
                                  MAT_F_DONT_COPY_DATA);
    if (var == nullptr || Mat_VarWrite(mat, var, MAT_COMPRESSION_ZLIB) != 0) {
      status = IoError(fmt::format("{}: cannot write variable {}", path, name));
    }
    if (var != nullptr) Mat_VarFree(var);
    if (!status.ok()) break;
  }
  if (Mat_Close(mat) != 0 && status.ok()) status = IoError(fmt::format("{}: cannot close", path));
  return status;
}

#else  // !GROVE_HAVE_MATIO

class MatFile::Handle {};

StatusOr<MatFile> MatFile::Open(const std::string& path) {
  return InvalidArgumentError(fmt::format(
      "{}: this grove was built without MAT file support (install libmatio-dev and rebuild)",
      path));
}
bool MatFile::Has(const std::string&) const { return false; }
StatusOr<MatMatrix> MatFile::ReadMatrix(const std::string& name) const {
  return InvalidArgumentError(fmt::format("{}: no MAT file support", path_));
}
Status WriteMatFile(const std::string& path,
                    const std::vector<std::pair<std::string, MatMatrix>>&) {
  return InvalidArgumentError(fmt::format(
      "{}: this grove was built without MAT file support (install libmatio-dev and rebuild)",
      path));
}

#endif  // GROVE_HAVE_MATIO

MatFile::MatFile(std::string path, std::unique_ptr<Handle> handle)
    : path_(std::move(path)), handle_(std::move(handle)) {}
MatFile::MatFile(MatFile&&) noexcept = default;
MatFile& MatFile::operator=(MatFile&&) noexcept = default;
MatFile::~MatFile() = default;

}  // namespace grove::tools
