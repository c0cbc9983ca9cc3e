#include "liquid/io/archive.hpp"

#include <fmt/format.h>
#include <hdf5.h>

#include <unistd.h>

#include <filesystem>
#include <utility>

#include "liquid/core/error.hpp"
#include "liquid/io/hdf5_detail.hpp"

namespace liquid::io::detail {

/// The open HDF5 file of an archive writer or reader.
class ArchiveFile {
 public:
  explicit ArchiveFile(hid_t file_id) : id(file_id) {}
  ~ArchiveFile() {
    if (id >= 0) H5Fclose(id);
  }
  ArchiveFile(const ArchiveFile&) = delete;
  ArchiveFile& operator=(const ArchiveFile&) = delete;
  hid_t id;
};

}  // namespace liquid::io::detail

namespace liquid::io {

using detail::Handle;
using detail::QuietHdf5;

namespace {

/// The HDF5 types of each element type: in memory, in the file, and the word errors use.
template <typename T>
struct Element;
template <>
struct Element<double> {
  static hid_t memory() { return H5T_NATIVE_DOUBLE; }
  static hid_t file() { return H5T_IEEE_F64LE; }
  static constexpr const char* word = "double";
};
template <>
struct Element<std::int32_t> {
  static hid_t memory() { return H5T_NATIVE_INT32; }
  static hid_t file() { return H5T_STD_I32LE; }
  static constexpr const char* word = "int32";
};
template <>
struct Element<std::int64_t> {
  static hid_t memory() { return H5T_NATIVE_INT64; }
  static hid_t file() { return H5T_STD_I64LE; }
  static constexpr const char* word = "int64";
};
template <>
struct Element<std::uint8_t> {
  static hid_t memory() { return H5T_NATIVE_UINT8; }
  static hid_t file() { return H5T_STD_U8LE; }
  static constexpr const char* word = "uint8";
};
template <>
struct Element<std::uint32_t> {
  static hid_t memory() { return H5T_NATIVE_UINT32; }
  static hid_t file() { return H5T_STD_U32LE; }
  static constexpr const char* word = "uint32";
};
template <>
struct Element<std::uint64_t> {
  static hid_t memory() { return H5T_NATIVE_UINT64; }
  static hid_t file() { return H5T_STD_U64LE; }
  static constexpr const char* word = "uint64";
};

/// The parts of a name ("a/b/c" -> a, a/b, a/b/c), or nothing when the name is malformed.
std::vector<std::string> prefixes(const std::string& name) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (true) {
    const std::size_t slash = name.find('/', start);
    const std::string part =
        name.substr(start, slash == std::string::npos ? std::string::npos : slash - start);
    if (!detail::valid_field_name(part) || part == "." || part == "..") return {};
    out.push_back(name.substr(0, slash));
    if (slash == std::string::npos) return out;
    start = slash + 1;
  }
}

/// The HDF5 id of an archive's open file; throws when there is none (a committed writer, a
/// moved-from reader or writer).
hid_t open_id(const std::unique_ptr<detail::ArchiveFile>& file, const std::string& path, const char* who) {
  LIQUID_VERIFY(file != nullptr, "{}: {} is closed (committed or moved from)", who, path);
  return file->id;
}

/// Whether `name` names an object (dataset or group) in `file`.
bool exists(hid_t file, const std::string& name) {
  const std::vector<std::string> parts = prefixes(name);
  if (parts.empty()) return false;
  QuietHdf5 quiet;
  for (const std::string& p : parts)
    if (H5Lexists(file, p.c_str(), H5P_DEFAULT) <= 0) return false;
  return true;
}

/// What a type is, in the words errors use ("double", "int32", "string", ...).
std::string type_word(hid_t type) {
  const std::size_t size = H5Tget_size(type);
  switch (H5Tget_class(type)) {
    case H5T_FLOAT:
      return size == 8 ? "double" : fmt::format("float{}", 8 * size);
    case H5T_INTEGER:
      return fmt::format("{}int{}", H5Tget_sign(type) == H5T_SGN_NONE ? "u" : "", 8 * size);
    case H5T_STRING:
      return H5Tis_variable_str(type) > 0 ? "variable-length string" : "string";
    default:
      return fmt::format("HDF5 type class {}", static_cast<int>(H5Tget_class(type)));
  }
}

/// What a dataset holds, in the words errors use: "a 1-D array of int32", "a scalar double",
/// "a string" (a scalar fixed-length string).
std::string holds(hid_t set) {
  Handle type(H5Dget_type(set), H5Tclose);
  Handle space(H5Dget_space(set), H5Sclose);
  if (!type.ok() || !space.ok()) return "an unreadable dataset";
  const std::string word = type_word(type.get());
  switch (H5Sget_simple_extent_type(space.get())) {
    case H5S_SCALAR:
      return word == "string" ? "a string" : "a scalar " + word;
    case H5S_SIMPLE:
      return fmt::format("a {}-D array of {}", H5Sget_simple_extent_ndims(space.get()), word);
    default:
      return "an empty (null) dataspace of " + word;
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// ArchiveWriter

ArchiveWriter::ArchiveWriter(std::string path) : path_(std::move(path)) {
  const std::string tmp = path_ + ".tmp";
  // The file is built in memory and written in one piece by commit() (detail::create_memory_file);
  // a folder that cannot take it is named now, before anything is stored.
  const std::filesystem::path folder = std::filesystem::path(tmp).parent_path();
  const std::string where = folder.empty() ? std::string(".") : folder.string();
  LIQUID_VERIFY(std::filesystem::is_directory(where) && ::access(where.c_str(), W_OK) == 0,
                "ArchiveWriter: cannot create {} (does its folder exist and is it writable?)", tmp);
  QuietHdf5 quiet;
  const hid_t id = detail::create_memory_file(tmp, "ArchiveWriter");
  LIQUID_VERIFY(id >= 0, "ArchiveWriter: cannot create the HDF5 file {} in memory", tmp);
  file_ = std::make_unique<detail::ArchiveFile>(id);
}

ArchiveWriter::~ArchiveWriter() {
  if (!file_) return;
  file_.reset();
  std::error_code ec;
  std::filesystem::remove(path_ + ".tmp", ec);
}

ArchiveWriter::ArchiveWriter(ArchiveWriter&& other) noexcept
    : path_(std::move(other.path_)), file_(std::move(other.file_)) {}

ArchiveWriter& ArchiveWriter::operator=(ArchiveWriter&& other) noexcept {
  // The old file of this writer goes to `other`, whose destructor removes it uncommitted.
  std::swap(path_, other.path_);
  std::swap(file_, other.file_);
  return *this;
}

namespace {

/// Creates dataset `name` (and the groups above it) in an archive being written, and writes it.
void create(hid_t file, const std::string& path, const std::string& name, hid_t mem_type, hid_t file_type,
            hid_t space, const void* data, bool empty) {
  const std::string tmp = path + ".tmp";
  LIQUID_VERIFY(!prefixes(name).empty(),
                "ArchiveWriter: bad name '{}' for {} (parts joined by '/', each of letters, digits, '_', "
                "'-', '.', and not '.' or '..')",
                name, path);
  LIQUID_VERIFY(!exists(file, name), "ArchiveWriter: {} already holds '{}'", tmp, name);
  QuietHdf5 quiet;
  Handle lcpl(H5Pcreate(H5P_LINK_CREATE), H5Pclose);
  LIQUID_VERIFY(lcpl.ok() && H5Pset_create_intermediate_group(lcpl.get(), 1) >= 0,
                "ArchiveWriter: cannot set up the creation of '{}' in {}", name, tmp);
  Handle set(H5Dcreate2(file, name.c_str(), file_type, space, lcpl.get(), H5P_DEFAULT, H5P_DEFAULT),
             H5Dclose);
  LIQUID_VERIFY(set.ok(),
                "ArchiveWriter: cannot create dataset '{}' in {} (is a part of its name a dataset?)", name,
                tmp);
  if (empty) return;
  LIQUID_VERIFY(H5Dwrite(set.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) >= 0,
                "ArchiveWriter: cannot write dataset '{}' in {}", name, tmp);
}

template <typename T>
void put_array(hid_t file, const std::string& path, const std::string& name, std::span<const T> values) {
  const hsize_t n = values.size();
  Handle space(H5Screate_simple(1, &n, nullptr), H5Sclose);
  LIQUID_VERIFY(space.ok(), "ArchiveWriter: cannot make the dataspace of '{}' for {}", name, path);
  create(file, path, name, Element<T>::memory(), Element<T>::file(), space.get(), values.data(), n == 0);
}

template <typename T>
void put_one(hid_t file, const std::string& path, const std::string& name, T value) {
  Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  LIQUID_VERIFY(space.ok(), "ArchiveWriter: cannot make the dataspace of '{}' for {}", name, path);
  create(file, path, name, Element<T>::memory(), Element<T>::file(), space.get(), &value, false);
}

}  // namespace

void ArchiveWriter::put(const std::string& name, std::span<const double> values) {
  put_array(open_id(file_, path_, "ArchiveWriter"), path_, name, values);
}
void ArchiveWriter::put(const std::string& name, std::span<const std::int32_t> values) {
  put_array(open_id(file_, path_, "ArchiveWriter"), path_, name, values);
}
void ArchiveWriter::put(const std::string& name, std::span<const std::int64_t> values) {
  put_array(open_id(file_, path_, "ArchiveWriter"), path_, name, values);
}
void ArchiveWriter::put(const std::string& name, std::span<const std::uint8_t> values) {
  put_array(open_id(file_, path_, "ArchiveWriter"), path_, name, values);
}
void ArchiveWriter::put(const std::string& name, std::span<const std::uint32_t> values) {
  put_array(open_id(file_, path_, "ArchiveWriter"), path_, name, values);
}
void ArchiveWriter::put(const std::string& name, std::span<const std::uint64_t> values) {
  put_array(open_id(file_, path_, "ArchiveWriter"), path_, name, values);
}
void ArchiveWriter::put_scalar(const std::string& name, double value) {
  put_one(open_id(file_, path_, "ArchiveWriter"), path_, name, value);
}
void ArchiveWriter::put_scalar(const std::string& name, std::int64_t value) {
  put_one(open_id(file_, path_, "ArchiveWriter"), path_, name, value);
}

void ArchiveWriter::put_string(const std::string& name, const std::string& value) {
  const hid_t file = open_id(file_, path_, "ArchiveWriter");
  // Length + 1 bytes, the last the terminating NUL: other readers see a C string, ours takes the
  // first size - 1 bytes, so NULs inside the string survive.
  Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
  LIQUID_VERIFY(type.ok() && H5Tset_size(type.get(), value.size() + 1) >= 0 &&
                    H5Tset_strpad(type.get(), H5T_STR_NULLTERM) >= 0,
                "ArchiveWriter: cannot make the string type of '{}' for {}", name, path_);
  Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  LIQUID_VERIFY(space.ok(), "ArchiveWriter: cannot make the dataspace of '{}' for {}", name, path_);
  create(file, path_, name, type.get(), type.get(), space.get(), value.c_str(), false);
}

void ArchiveWriter::commit() {
  open_id(file_, path_, "ArchiveWriter");
  const std::string tmp = path_ + ".tmp";
  {
    QuietHdf5 quiet;
    detail::save_memory_file(file_->id, tmp, "ArchiveWriter");
    const herr_t closed = H5Fclose(std::exchange(file_->id, -1));
    LIQUID_VERIFY(closed >= 0, "ArchiveWriter: cannot close {}", tmp);
  }
  detail::rename_file(tmp, path_, "ArchiveWriter");
  file_.reset();
}

// ---------------------------------------------------------------------------------------------
// ArchiveReader

ArchiveReader::ArchiveReader(std::string path) : path_(std::move(path)) {
  QuietHdf5 quiet;
  LIQUID_VERIFY(std::filesystem::exists(path_), "ArchiveReader: {} does not exist", path_);
  const hid_t id = H5Fopen(path_.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  LIQUID_VERIFY(id >= 0, "ArchiveReader: cannot open {} (is it an HDF5 file?)", path_);
  file_ = std::make_unique<detail::ArchiveFile>(id);
}

ArchiveReader::~ArchiveReader() = default;
ArchiveReader::ArchiveReader(ArchiveReader&&) noexcept = default;
ArchiveReader& ArchiveReader::operator=(ArchiveReader&&) noexcept = default;

bool ArchiveReader::has(const std::string& name) const {
  return exists(open_id(file_, path_, "ArchiveReader"), name);
}

namespace {

/// Opens dataset `name` of the archive `path`, checking that it holds `expected` (in the words of
/// holds()); throws naming the file, the name, the expectation and what was found.
Handle open_checked(hid_t file, const std::string& path, const std::string& name,
                    const std::string& expected) {
  LIQUID_VERIFY(exists(file, name), "ArchiveReader: {} holds no '{}' (expected {})", path, name, expected);
  QuietHdf5 quiet;
  Handle object(H5Oopen(file, name.c_str(), H5P_DEFAULT), H5Oclose);
  LIQUID_VERIFY(object.ok(), "ArchiveReader: cannot open '{}' in {}", name, path);
  LIQUID_VERIFY(H5Iget_type(object.get()) == H5I_DATASET, "ArchiveReader: '{}' in {} is a group, expected {}",
                name, path, expected);
  Handle set(H5Dopen2(file, name.c_str(), H5P_DEFAULT), H5Dclose);
  LIQUID_VERIFY(set.ok(), "ArchiveReader: cannot open dataset '{}' in {}", name, path);
  const std::string found = holds(set.get());
  LIQUID_VERIFY(found == expected, "ArchiveReader: '{}' in {} holds {}, expected {}", name, path, found,
                expected);
  return set;
}

/// An archive's datasets are stored whole and uncompressed: one claiming more bytes than the file
/// holds is damaged, and is refused before anything is allocated for it.
void check_fits(hid_t file, const std::string& path, const std::string& name, hsize_t n, std::size_t size) {
  hsize_t file_size = 0;
  LIQUID_VERIFY(H5Fget_filesize(file, &file_size) >= 0, "ArchiveReader: cannot read the size of {}", path);
  LIQUID_VERIFY(n <= file_size / size,
                "ArchiveReader: '{}' in {} claims {} values of {} bytes, more than the "
                "file's {} bytes (a damaged file)",
                name, path, n, size, file_size);
}

template <typename T>
std::vector<T> read_array(hid_t file, const std::string& path, const std::string& name) {
  const Handle set = open_checked(file, path, name, fmt::format("a 1-D array of {}", Element<T>::word));
  Handle space(H5Dget_space(set.get()), H5Sclose);
  hsize_t n = 0;
  LIQUID_VERIFY(space.ok() && H5Sget_simple_extent_dims(space.get(), &n, nullptr) == 1,
                "ArchiveReader: cannot read the size of '{}' in {}", name, path);
  check_fits(file, path, name, n, sizeof(T));
  std::vector<T> values(n);
  if (n == 0) return values;
  QuietHdf5 quiet;
  LIQUID_VERIFY(H5Dread(set.get(), Element<T>::memory(), H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()) >= 0,
                "ArchiveReader: cannot read '{}' in {}", name, path);
  return values;
}

template <typename T>
T read_one(hid_t file, const std::string& path, const std::string& name) {
  const Handle set = open_checked(file, path, name, fmt::format("a scalar {}", Element<T>::word));
  T value{};
  QuietHdf5 quiet;
  LIQUID_VERIFY(H5Dread(set.get(), Element<T>::memory(), H5S_ALL, H5S_ALL, H5P_DEFAULT, &value) >= 0,
                "ArchiveReader: cannot read '{}' in {}", name, path);
  return value;
}

}  // namespace

std::vector<double> ArchiveReader::doubles(const std::string& name) const {
  return read_array<double>(open_id(file_, path_, "ArchiveReader"), path_, name);
}
std::vector<std::int32_t> ArchiveReader::int32s(const std::string& name) const {
  return read_array<std::int32_t>(open_id(file_, path_, "ArchiveReader"), path_, name);
}
std::vector<std::int64_t> ArchiveReader::int64s(const std::string& name) const {
  return read_array<std::int64_t>(open_id(file_, path_, "ArchiveReader"), path_, name);
}
std::vector<std::uint8_t> ArchiveReader::uint8s(const std::string& name) const {
  return read_array<std::uint8_t>(open_id(file_, path_, "ArchiveReader"), path_, name);
}
std::vector<std::uint32_t> ArchiveReader::uint32s(const std::string& name) const {
  return read_array<std::uint32_t>(open_id(file_, path_, "ArchiveReader"), path_, name);
}
std::vector<std::uint64_t> ArchiveReader::uint64s(const std::string& name) const {
  return read_array<std::uint64_t>(open_id(file_, path_, "ArchiveReader"), path_, name);
}
double ArchiveReader::scalar_double(const std::string& name) const {
  return read_one<double>(open_id(file_, path_, "ArchiveReader"), path_, name);
}
std::int64_t ArchiveReader::scalar_int(const std::string& name) const {
  return read_one<std::int64_t>(open_id(file_, path_, "ArchiveReader"), path_, name);
}

std::string ArchiveReader::string(const std::string& name) const {
  const Handle set = open_checked(open_id(file_, path_, "ArchiveReader"), path_, name, "a string");
  QuietHdf5 quiet;
  Handle type(H5Dget_type(set.get()), H5Tclose);
  const std::size_t size = type.ok() ? H5Tget_size(type.get()) : 0;
  LIQUID_VERIFY(size > 0, "ArchiveReader: cannot read the string type of '{}' in {}", name, path_);
  check_fits(file_->id, path_, name, size, 1);
  std::string bytes(size, '\0');
  LIQUID_VERIFY(H5Dread(set.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, bytes.data()) >= 0,
                "ArchiveReader: cannot read '{}' in {}", name, path_);
  // Our strings end in exactly one terminating NUL; padded strings of other writers lose their pad.
  switch (H5Tget_strpad(type.get())) {
    case H5T_STR_NULLTERM:
      bytes.pop_back();
      break;
    case H5T_STR_NULLPAD:
      bytes.erase(bytes.find_last_not_of('\0') + 1);
      break;
    case H5T_STR_SPACEPAD:
      bytes.erase(bytes.find_last_not_of(' ') + 1);
      break;
    default:
      break;
  }
  return bytes;
}

}  // namespace liquid::io
