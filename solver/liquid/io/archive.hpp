#pragma once
// A small typed HDF5 archive for checkpoints: named 1-D arrays of doubles and integers, scalars and
// strings, read back exactly (bit for bit; only a NaN's payload may change).
//
// Names are paths: "particles/x" is dataset x in group particles (groups are made as needed). A
// name is one or more parts joined by '/', each part letters, digits, '_', '-' and '.' only, and not
// "." or "..". In the file, arrays are 1-D datasets of little-endian IEEE doubles or integers of the
// stated width and sign, scalars are scalar datasets (double or int64) and a string is a scalar
// fixed-length string of its length + 1 bytes (NUL-terminated for other readers; the length is
// exact for ours, so strings may hold any bytes).
//
// ArchiveWriter builds the file in memory, writes it whole to PATH.tmp and renames that to PATH
// only in commit(), so a run killed while writing a checkpoint leaves the previous PATH intact, and a
// full disk is one error naming the file and the reason; a writer destroyed without commit()
// removes PATH.tmp.

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace liquid::io::detail {
class ArchiveFile;  // the open HDF5 file (archive.cpp)
}  // namespace liquid::io::detail

namespace liquid::io {

class ArchiveWriter {
 public:
  /// Starts PATH's file in memory; throws liquid::Error naming PATH.tmp unless PATH's folder exists
  /// and is writable.
  explicit ArchiveWriter(std::string path);
  ~ArchiveWriter();
  ArchiveWriter(ArchiveWriter&&) noexcept;
  ArchiveWriter& operator=(ArchiveWriter&&) noexcept;
  ArchiveWriter(const ArchiveWriter&) = delete;
  ArchiveWriter& operator=(const ArchiveWriter&) = delete;

  /// Stores `values` as the 1-D array `name` (may be empty). A name may be stored once; every put
  /// throws liquid::Error on a bad or taken name, after commit(), or when HDF5 fails.
  void put(const std::string& name, std::span<const double> values);
  void put(const std::string& name, std::span<const std::int32_t> values);
  void put(const std::string& name, std::span<const std::int64_t> values);
  void put(const std::string& name, std::span<const std::uint8_t> values);
  void put(const std::string& name, std::span<const std::uint32_t> values);
  void put(const std::string& name, std::span<const std::uint64_t> values);
  /// Stores a scalar double or int64 (an int argument is ambiguous: say which).
  void put_scalar(const std::string& name, double value);
  void put_scalar(const std::string& name, std::int64_t value);
  /// Stores a string (any bytes, NUL included).
  void put_string(const std::string& name, const std::string& value);

  /// Writes the file to PATH.tmp, then renames it to PATH (replacing an older PATH). Once only.
  void commit();

  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::unique_ptr<detail::ArchiveFile> file_;  ///< null after commit()
};

class ArchiveReader {
 public:
  /// Opens PATH read-only; throws liquid::Error naming it when it is missing or not HDF5.
  explicit ArchiveReader(std::string path);
  ~ArchiveReader();
  ArchiveReader(ArchiveReader&&) noexcept;
  ArchiveReader& operator=(ArchiveReader&&) noexcept;
  ArchiveReader(const ArchiveReader&) = delete;
  ArchiveReader& operator=(const ArchiveReader&) = delete;

  /// The 1-D array `name`. A missing name or one that holds something else (another type or width,
  /// a scalar, a string, a group) throws liquid::Error naming the file, the name, what was expected
  /// and what was found.
  std::vector<double> doubles(const std::string& name) const;
  std::vector<std::int32_t> int32s(const std::string& name) const;
  std::vector<std::int64_t> int64s(const std::string& name) const;
  std::vector<std::uint8_t> uint8s(const std::string& name) const;
  std::vector<std::uint32_t> uint32s(const std::string& name) const;
  std::vector<std::uint64_t> uint64s(const std::string& name) const;
  /// The scalar `name` (stored by put_scalar); errors as for the arrays.
  double scalar_double(const std::string& name) const;
  std::int64_t scalar_int(const std::string& name) const;
  /// The string `name` (stored by put_string); errors as for the arrays.
  std::string string(const std::string& name) const;
  /// Whether the archive holds a dataset or group `name` (false for a malformed name).
  bool has(const std::string& name) const;

  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::unique_ptr<detail::ArchiveFile> file_;
};

}  // namespace liquid::io
