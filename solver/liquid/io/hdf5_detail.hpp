#pragma once
// Private to the io module: the HDF5 and file helpers its writers share. Included only by the
// module's .cpp files (HDF5 is a private dependency, so no public header may include this one).

#include <hdf5.h>

#include <cctype>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "liquid/core/error.hpp"
#include "liquid/io/files.hpp"

namespace liquid::io::detail {

/// Silences HDF5's own error printing while alive (our checks report failures), then restores it.
class QuietHdf5 {
 public:
  QuietHdf5() {
    H5Eget_auto2(H5E_DEFAULT, &func_, &data_);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  }
  ~QuietHdf5() { H5Eset_auto2(H5E_DEFAULT, func_, data_); }
  QuietHdf5(const QuietHdf5&) = delete;
  QuietHdf5& operator=(const QuietHdf5&) = delete;

 private:
  H5E_auto2_t func_ = nullptr;
  void* data_ = nullptr;
};

/// Closes an HDF5 handle on scope exit.
class Handle {
 public:
  Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  ~Handle() {
    if (id_ >= 0) close_(id_);
  }
  Handle(Handle&& other) noexcept : id_(std::exchange(other.id_, -1)), close_(other.close_) {}
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  Handle& operator=(Handle&&) = delete;
  hid_t get() const { return id_; }
  bool ok() const { return id_ >= 0; }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

/// Creates an HDF5 file held in memory (the core driver without a backing store), to be written to
/// disk in one piece by save_memory_file(): nothing reaches the disk while datasets are added, so a
/// full disk is one error from our own write, naming the file and the system's reason, and the
/// library is never left holding a half-written file it cannot flush or close. -1 on failure.
inline hid_t create_memory_file(const std::string& path, std::string_view who) {
  Handle fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  LIQUID_VERIFY(fapl.ok() && H5Pset_fapl_core(fapl.get(), std::size_t{1} << 20, 0) >= 0,
                "{}: cannot set up the in-memory HDF5 file for {}", who, path);
  return H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get());
}

/// Writes the in-memory HDF5 file `file` as it stands to `path`; throws naming it (and removes it)
/// on failure.
inline void save_memory_file(hid_t file, const std::string& path, std::string_view who) {
  LIQUID_VERIFY(H5Fflush(file, H5F_SCOPE_GLOBAL) >= 0, "{}: cannot finish the HDF5 file {} in memory", who,
                path);
  const ssize_t size = H5Fget_file_image(file, nullptr, 0);
  LIQUID_VERIFY(size > 0, "{}: cannot read back the HDF5 file {} from memory", who, path);
  std::string image(static_cast<std::size_t>(size), '\0');
  LIQUID_VERIFY(H5Fget_file_image(file, image.data(), image.size()) == size,
                "{}: cannot read back the HDF5 file {} from memory", who, path);
  write_file(path, image, who);
}

/// An in-memory HDF5 file (create_memory_file) closed on scope exit.
class MemoryFile {
 public:
  MemoryFile(const std::string& path, std::string_view who) : file_(create_memory_file(path, who), H5Fclose) {
    LIQUID_VERIFY(file_.ok(), "{}: cannot create the HDF5 file {} in memory", who, path);
  }
  hid_t get() const { return file_.get(); }
  void save(const std::string& path, std::string_view who) const { save_memory_file(file_.get(), path, who); }

 private:
  Handle file_;
};

/// Removes the temporaries of a write that did not finish (a throw before release()).
class TemporaryFiles {
 public:
  explicit TemporaryFiles(std::vector<std::string> paths) : paths_(std::move(paths)) {}
  ~TemporaryFiles() {
    std::error_code ignored;
    for (const std::string& p : paths_) std::filesystem::remove(p, ignored);
  }
  TemporaryFiles(const TemporaryFiles&) = delete;
  TemporaryFiles& operator=(const TemporaryFiles&) = delete;
  /// The write finished: the temporaries have been renamed into place.
  void release() { paths_.clear(); }

 private:
  std::vector<std::string> paths_;
};

/// Creates dataset `name` under `where` with `dims` and writes `data` (which may be null when a
/// dimension is 0). `who` starts every message ("write_tree"), `path` is the file named in it.
inline void write_dataset(hid_t where, const std::string& name, hid_t mem_type, hid_t file_type,
                          std::vector<hsize_t> dims, const void* data, const std::string& path,
                          std::string_view who) {
  Handle space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), H5Sclose);
  LIQUID_VERIFY(space.ok(), "{}: cannot make the dataspace of {} in {}", who, name, path);
  Handle set(H5Dcreate2(where, name.c_str(), file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
             H5Dclose);
  LIQUID_VERIFY(set.ok(), "{}: cannot create dataset {} in {}", who, name, path);
  hsize_t n = 1;
  for (hsize_t d : dims) n *= d;
  if (n == 0) return;  // an empty dataset has nothing to write (and HDF5 refuses a null buffer)
  LIQUID_VERIFY(H5Dwrite(set.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) >= 0,
                "{}: cannot write dataset {} in {}", who, name, path);
}

/// A field name: non-empty, letters, digits, '_', '-' and '.' only (safe as an HDF5 dataset name,
/// an XML attribute value and a ParaView array name).
inline bool valid_field_name(const std::string& name) {
  if (name.empty()) return false;
  for (char ch : name)
    if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-' || ch == '.')) return false;
  return true;
}

inline std::string data_item(const std::string& dims, const char* type, int precision,
                             const std::string& ref) {
  return fmt::format(R"(<DataItem Dimensions="{}" NumberType="{}" Precision="{}" Format="HDF">{}</DataItem>)",
                     dims, type, precision, ref);
}

/// `text` with `n` spaces before every non-empty line.
inline std::string indent(const std::string& text, int n) {
  std::string out;
  const std::string pad(static_cast<std::size_t>(n), ' ');
  bool line_start = true;
  for (char ch : text) {
    if (line_start && ch != '\n') out += pad;
    out += ch;
    line_start = ch == '\n';
  }
  return out;
}

/// A complete XDMF 3 document whose Domain holds `grid` (one <Grid>...</Grid> element).
inline std::string xdmf_document(const std::string& grid) {
  return "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n<Xdmf Version=\"3.0\">\n  "
         "<Domain>\n" +
         indent(grid, 4) + "\n  </Domain>\n</Xdmf>\n";
}

/// Renames `from` to `to`, replacing `to`; throws naming both when that fails.
inline void rename_file(const std::string& from, const std::string& to, std::string_view who) {
  std::error_code ec;
  std::filesystem::rename(from, to, ec);
  LIQUID_VERIFY(!ec, "{}: cannot rename {} to {}: {}", who, from, to, ec.message());
}

}  // namespace liquid::io::detail
