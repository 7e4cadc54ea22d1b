// The one HDF5 layer over the HDF5 C library: identifiers closed by RAII, object time stamps off.
#include "core/hdf5_file.hpp"

#include <hdf5.h>

#include <algorithm>
#include <functional>
#include <numeric>
#include <type_traits>
#include <utility>

#include "core/error.hpp"
#include "core/hdf5_root_check.hpp"

namespace glaswave {
namespace {

// An HDF5 identifier closed with its own close function when it goes.
class Handle {
 public:
  Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  Handle(Handle&& other) noexcept : id_(std::exchange(other.id_, -1)), close_(other.close_) {}
  Handle& operator=(Handle&& other) noexcept {
    if (this != &other) {
      reset();
      id_ = std::exchange(other.id_, -1);
      close_ = other.close_;
    }
    return *this;
  }
  ~Handle() { reset(); }
  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }
  // Closes now; false when HDF5 could not (a flush that failed).
  bool reset() {
    const bool ok = id_ < 0 || close_(id_) >= 0;
    id_ = -1;
    return ok;
  }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

template <typename T>
struct Type;
#define GLASWAVE_HDF5_TYPE(T, FILE, MEMORY)  \
  template <>                                \
  struct Type<T> {                           \
    static hid_t file() { return FILE; }     \
    static hid_t memory() { return MEMORY; } \
  };
GLASWAVE_HDF5_TYPE(double, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE)
GLASWAVE_HDF5_TYPE(float, H5T_IEEE_F32LE, H5T_NATIVE_FLOAT)
GLASWAVE_HDF5_TYPE(std::int64_t, H5T_STD_I64LE, H5T_NATIVE_INT64)
GLASWAVE_HDF5_TYPE(std::uint64_t, H5T_STD_U64LE, H5T_NATIVE_UINT64)
GLASWAVE_HDF5_TYPE(std::int32_t, H5T_STD_I32LE, H5T_NATIVE_INT32)
GLASWAVE_HDF5_TYPE(std::uint32_t, H5T_STD_U32LE, H5T_NATIVE_UINT32)
GLASWAVE_HDF5_TYPE(std::uint16_t, H5T_STD_U16LE, H5T_NATIVE_UINT16)
GLASWAVE_HDF5_TYPE(std::int16_t, H5T_STD_I16LE, H5T_NATIVE_INT16)
GLASWAVE_HDF5_TYPE(std::int8_t, H5T_STD_I8LE, H5T_NATIVE_INT8)
GLASWAVE_HDF5_TYPE(std::uint8_t, H5T_STD_U8LE, H5T_NATIVE_UINT8)
#undef GLASWAVE_HDF5_TYPE

// Arrays above this many values are chunked and deflated.
constexpr std::size_t kChunkedFrom = 4096;
constexpr hsize_t kChunkValues = 65536;
constexpr hsize_t kGranuleChunkRows = 10000;  // Hdf5Chunking::every

// A fixed-length, null-terminated text type of `text`'s length (one byte for none).
Handle text_type(const std::string& text) {
  Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
  if (type.valid()) {
    H5Tset_size(type.get(), std::max<std::size_t>(text.size(), 1));
    H5Tset_strpad(type.get(), H5T_STR_NULLTERM);
  }
  return type;
}

}  // namespace

void quiet_hdf5_in_this_thread() {
  thread_local bool quiet = false;
  if (quiet) return;
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  quiet = true;
}

struct Hdf5Writer::Impl {
  std::string path;
  Handle file{-1, H5Fclose};
  Handle object{-1, H5Pclose};  // groups without time stamps
  Hdf5Chunking chunking = Hdf5Chunking::large;

  // Makes the groups on `path` above its last part, each without time stamps (groups HDF5
  // made itself as intermediates would carry them).
  void parents(const std::string& path) const {
    for (std::size_t slash = path.find('/', 1); slash != std::string::npos;
         slash = path.find('/', slash + 1)) {
      const std::string part = path.substr(0, slash);
      if (H5Lexists(file.get(), part.c_str(), H5P_DEFAULT) > 0) continue;
      Handle g(H5Gcreate2(file.get(), part.c_str(), H5P_DEFAULT, object.get(), H5P_DEFAULT),
               H5Gclose);
      check(g.valid(), "cannot create the group " + part);
    }
  }

  void check(bool ok, const std::string& what) const {
    if (!ok) throw run_error(path, what);
  }

  // A dataset's creation properties: no time stamps, its chunks and its fill value.
  Handle creation(const std::vector<hsize_t>& dims, std::size_t count) const {
    Handle create(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
    check(create.valid() && H5Pset_obj_track_times(create.get(), false) >= 0,
          "cannot set a dataset's properties");
    // An empty dataset stays contiguous: a chunk may not exceed its fixed dimensions.
    const bool every = chunking == Hdf5Chunking::every && count > 0;
    if (count > kChunkedFrom || every) {
      // Chunks of whole rows (a shot's 101 rh, its bins): about 64k values each, or
      // kGranuleChunkRows rows.
      std::vector<hsize_t> chunk = dims;
      const hsize_t row = static_cast<hsize_t>(count) / dims[0];
      chunk[0] = every
                     ? std::min<hsize_t>(dims[0], kGranuleChunkRows)
                     : std::max<hsize_t>(
                           1, std::min<hsize_t>(dims[0], kChunkValues / std::max<hsize_t>(row, 1)));
      H5Pset_chunk(create.get(), static_cast<int>(chunk.size()), chunk.data());
      H5Pset_shuffle(create.get());
      H5Pset_deflate(create.get(), 4);
    }
    return create;
  }

  void attributes(const std::string& object_path, const std::vector<Hdf5Attribute>& list,
                  Hdf5Writer& writer) const {
    for (const Hdf5Attribute& a : list) writer.text_attribute(object_path, a.name, a.value);
  }
};

Hdf5Writer::Hdf5Writer(const std::filesystem::path& path, Hdf5Chunking chunking)
    : impl_(std::make_unique<Impl>()) {
  impl_->path = path.string();
  impl_->chunking = chunking;
  quiet_hdf5_in_this_thread();
  // The root group too is made without time stamps (a file's creation properties are a
  // group's).
  Handle file_create(H5Pcreate(H5P_FILE_CREATE), H5Pclose);
  impl_->check(file_create.valid() && H5Pset_obj_track_times(file_create.get(), false) >= 0,
               "cannot create the file");
  impl_->file = Handle(
      H5Fcreate(impl_->path.c_str(), H5F_ACC_TRUNC, file_create.get(), H5P_DEFAULT), H5Fclose);
  impl_->check(impl_->file.valid(), "cannot create the file");
  impl_->object = Handle(H5Pcreate(H5P_GROUP_CREATE), H5Pclose);
  impl_->check(impl_->object.valid() && H5Pset_obj_track_times(impl_->object.get(), false) >= 0,
               "cannot create the file");
}

Hdf5Writer::~Hdf5Writer() = default;

void Hdf5Writer::group(const std::string& path) {
  Impl& m = *impl_;
  m.parents(path);
  if (H5Lexists(m.file.get(), path.c_str(), H5P_DEFAULT) > 0) return;
  Handle g(H5Gcreate2(m.file.get(), path.c_str(), H5P_DEFAULT, m.object.get(), H5P_DEFAULT),
           H5Gclose);
  m.check(g.valid(), "cannot create the group " + path);
}

void Hdf5Writer::text_attribute(const std::string& object, const std::string& name,
                                const std::string& value) {
  Impl& m = *impl_;
  const Handle type = text_type(value);
  Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  Handle attr(type.valid() && space.valid()
                  ? H5Acreate_by_name(m.file.get(), object.c_str(), name.c_str(), type.get(),
                                      space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT)
                  : -1,
              H5Aclose);
  m.check(attr.valid() && H5Awrite(attr.get(), type.get(), value.c_str()) >= 0,
          "cannot write the attribute " + name + " of " + object);
}

void Hdf5Writer::double_attribute(const std::string& object, const std::string& name,
                                  double value) {
  Impl& m = *impl_;
  Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  Handle attr(space.valid()
                  ? H5Acreate_by_name(m.file.get(), object.c_str(), name.c_str(), H5T_IEEE_F64LE,
                                      space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT)
                  : -1,
              H5Aclose);
  m.check(attr.valid() && H5Awrite(attr.get(), H5T_NATIVE_DOUBLE, &value) >= 0,
          "cannot write the attribute " + name + " of " + object);
}

void Hdf5Writer::double_array_attribute(const std::string& object, const std::string& name,
                                        const std::vector<double>& values,
                                        const std::vector<std::uint64_t>& dims_in) {
  Impl& m = *impl_;
  const std::vector<hsize_t> dims(dims_in.begin(), dims_in.end());
  const hsize_t total =
      std::accumulate(dims.begin(), dims.end(), hsize_t{1}, std::multiplies<hsize_t>());
  m.check(!dims.empty() && total == values.size(),
          "internal: the attribute " + name + " of " + object + " has " +
              std::to_string(values.size()) + " values for its dimensions");
  Handle space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), H5Sclose);
  Handle attr(space.valid()
                  ? H5Acreate_by_name(m.file.get(), object.c_str(), name.c_str(), H5T_IEEE_F64LE,
                                      space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT)
                  : -1,
              H5Aclose);
  m.check(attr.valid() && H5Awrite(attr.get(), H5T_NATIVE_DOUBLE, values.data()) >= 0,
          "cannot write the attribute " + name + " of " + object);
}

template <typename T>
void Hdf5Writer::write(const std::string& path, const std::vector<T>& values,
                       const std::vector<Hdf5Attribute>& attributes,
                       const std::vector<std::uint64_t>& dims_in, std::optional<T> fill) {
  Impl& m = *impl_;
  std::vector<hsize_t> dims(dims_in.begin(), dims_in.end());
  if (dims.empty()) dims = {static_cast<hsize_t>(values.size())};
  const hsize_t total =
      std::accumulate(dims.begin(), dims.end(), hsize_t{1}, std::multiplies<hsize_t>());
  m.check(total == values.size(), "internal: " + path + " has " + std::to_string(values.size()) +
                                      " values for its dimensions");
  Handle space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), H5Sclose);
  m.check(space.valid(), "cannot write " + path);
  const Handle create = m.creation(dims, values.size());
  if (fill) H5Pset_fill_value(create.get(), Type<T>::memory(), &*fill);
  m.parents(path);
  Handle set(H5Dcreate2(m.file.get(), path.c_str(), Type<T>::file(), space.get(), H5P_DEFAULT,
                        create.get(), H5P_DEFAULT),
             H5Dclose);
  m.check(set.valid() && (values.empty() || H5Dwrite(set.get(), Type<T>::memory(), H5S_ALL, H5S_ALL,
                                                     H5P_DEFAULT, values.data()) >= 0),
          "cannot write " + path);
  set.reset();
  m.attributes(path, attributes, *this);
  if (fill) {
    Handle scalar(H5Screate(H5S_SCALAR), H5Sclose);
    Handle attr(H5Acreate_by_name(m.file.get(), path.c_str(), "_FillValue", Type<T>::file(),
                                  scalar.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                H5Aclose);
    m.check(attr.valid() && H5Awrite(attr.get(), Type<T>::memory(), &*fill) >= 0,
            "cannot write the _FillValue of " + path);
  }
}

#define GLASWAVE_HDF5_WRITE(T)                                               \
  template void Hdf5Writer::write(const std::string&, const std::vector<T>&, \
                                  const std::vector<Hdf5Attribute>&,         \
                                  const std::vector<std::uint64_t>&, std::optional<T>);
GLASWAVE_HDF5_WRITE(double)
GLASWAVE_HDF5_WRITE(float)
GLASWAVE_HDF5_WRITE(std::int64_t)
GLASWAVE_HDF5_WRITE(std::uint64_t)
GLASWAVE_HDF5_WRITE(std::int32_t)
GLASWAVE_HDF5_WRITE(std::uint32_t)
GLASWAVE_HDF5_WRITE(std::uint16_t)
GLASWAVE_HDF5_WRITE(std::int16_t)
GLASWAVE_HDF5_WRITE(std::int8_t)
GLASWAVE_HDF5_WRITE(std::uint8_t)
#undef GLASWAVE_HDF5_WRITE

void Hdf5Writer::write_text(const std::string& path, const std::string& text,
                            const std::vector<Hdf5Attribute>& attributes) {
  Impl& m = *impl_;
  const Handle type = text_type(text);
  const hsize_t one = 1;
  Handle space(H5Screate_simple(1, &one, nullptr), H5Sclose);
  const Handle create = m.creation({one}, 1);
  m.parents(path);
  Handle set(type.valid() && space.valid()
                 ? H5Dcreate2(m.file.get(), path.c_str(), type.get(), space.get(), H5P_DEFAULT,
                              create.get(), H5P_DEFAULT)
                 : -1,
             H5Dclose);
  m.check(set.valid() &&
              H5Dwrite(set.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, text.c_str()) >= 0,
          "cannot write " + path);
  set.reset();
  m.attributes(path, attributes, *this);
}

void Hdf5Writer::close() {
  Impl& m = *impl_;
  m.check(H5Fflush(m.file.get(), H5F_SCOPE_GLOBAL) >= 0, "cannot write the file (disk full?)");
  m.object.reset();
  m.check(m.file.reset(), "cannot close the file (disk full?)");
}

struct Hdf5Reader::Impl {
  Handle file{-1, H5Fclose};
};

bool Hdf5Reader::is_hdf5(const std::filesystem::path& path) {
  quiet_hdf5_in_this_thread();
  return H5Fis_hdf5(path.c_str()) > 0;
}

Hdf5Reader::Hdf5Reader(const std::filesystem::path& path) : impl_(std::make_unique<Impl>()) {
  // What HDF5 1.10 crashes on is refused before it reads the file (a library must not fork to
  // survive it).
  if (const auto fault = hdf5_root_fault(path))
    throw input_error(path.string(), "the HDF5 file is corrupt: " + *fault);
  quiet_hdf5_in_this_thread();
  impl_->file = Handle(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!impl_->file.valid()) throw input_error(path.string(), "cannot open the HDF5 file");
}

Hdf5Reader::~Hdf5Reader() = default;

bool Hdf5Reader::has(const std::string& path) const {
  // Every part of the path must exist before H5Lexists may be asked about the next.
  std::size_t slash = 0;
  while (true) {
    slash = path.find('/', slash + 1);
    const std::string part = path.substr(0, slash);
    if (H5Lexists(impl_->file.get(), part.c_str(), H5P_DEFAULT) <= 0) return false;
    if (slash == std::string::npos) return true;
  }
}

bool Hdf5Reader::is_group(const std::string& path) const {
  if (!has(path)) return false;
  const Handle group(H5Gopen2(impl_->file.get(), path.c_str(), H5P_DEFAULT), H5Gclose);
  return group.valid();
}

std::vector<std::string> Hdf5Reader::children(const std::string& path) const {
  std::vector<std::string> names;
  Handle group(H5Gopen2(impl_->file.get(), path.c_str(), H5P_DEFAULT), H5Gclose);
  if (!group.valid()) return names;
  H5Literate(
      group.get(), H5_INDEX_NAME, H5_ITER_INC, nullptr,
      [](hid_t, const char* name, const H5L_info_t*, void* data) -> herr_t {
        static_cast<std::vector<std::string>*>(data)->push_back(name);
        return 0;
      },
      &names);
  return names;
}

std::optional<Hdf5DatasetShape> Hdf5Reader::shape(const std::string& path) const {
  if (!has(path)) return std::nullopt;
  Handle set(H5Dopen2(impl_->file.get(), path.c_str(), H5P_DEFAULT), H5Dclose);
  if (!set.valid()) return std::nullopt;
  Hdf5DatasetShape shape;
  Handle space(H5Dget_space(set.get()), H5Sclose);
  const int rank = space.valid() ? H5Sget_simple_extent_ndims(space.get()) : -1;
  if (rank < 0) return std::nullopt;
  std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
  if (rank > 0) H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  shape.dims.assign(dims.begin(), dims.end());
  Handle type(H5Dget_type(set.get()), H5Tclose);
  const H5T_class_t type_class = type.valid() ? H5Tget_class(type.get()) : H5T_NO_CLASS;
  // A corrupt header may declare a number of a billion bytes, which HDF5 would convert through a
  // buffer of that size per value: numbers are at most 16 bytes (a long double).
  const std::size_t type_bytes = type.valid() ? H5Tget_size(type.get()) : 0;
  const bool sized = type_bytes >= 1 && type_bytes <= 16;
  shape.integer = sized && type_class == H5T_INTEGER;
  shape.numeric = shape.integer || (sized && type_class == H5T_FLOAT);
  shape.is_signed = shape.integer && H5Tget_sign(type.get()) == H5T_SGN_2;
  return shape;
}

template <typename T>
bool Hdf5Reader::read(const std::string& path, std::vector<T>& values) const {
  static_assert(std::is_same_v<T, double> || std::is_same_v<T, std::int64_t> ||
                std::is_same_v<T, std::uint64_t>);
  Handle set(H5Dopen2(impl_->file.get(), path.c_str(), H5P_DEFAULT), H5Dclose);
  if (!set.valid()) return false;
  Handle space(H5Dget_space(set.get()), H5Sclose);
  const hssize_t count = space.valid() ? H5Sget_simple_extent_npoints(space.get()) : -1;
  if (count < 0) return false;
  values.assign(static_cast<std::size_t>(count), T{});
  return count == 0 ||
         H5Dread(set.get(), Type<T>::memory(), H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()) >= 0;
}

bool Hdf5Reader::read_attribute(const std::string& object, const std::string& name,
                                std::size_t most, std::vector<double>& values,
                                std::vector<std::uint64_t>& dims) const {
  const hid_t file = impl_->file.get();
  if ((object != "/" && !has(object)) ||
      H5Aexists_by_name(file, object.c_str(), name.c_str(), H5P_DEFAULT) <= 0)
    return false;
  const Handle attr(H5Aopen_by_name(file, object.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT),
                    H5Aclose);
  if (!attr.valid()) return false;
  const Handle type(H5Aget_type(attr.get()), H5Tclose);
  const H5T_class_t type_class = type.valid() ? H5Tget_class(type.get()) : H5T_NO_CLASS;
  const std::size_t type_bytes = type.valid() ? H5Tget_size(type.get()) : 0;
  if ((type_class != H5T_INTEGER && type_class != H5T_FLOAT) || type_bytes < 1 || type_bytes > 16)
    return false;
  const Handle space(H5Aget_space(attr.get()), H5Sclose);
  const int rank = space.valid() ? H5Sget_simple_extent_ndims(space.get()) : -1;
  const hssize_t count = space.valid() ? H5Sget_simple_extent_npoints(space.get()) : -1;
  if (rank < 0 || count < 0 || static_cast<std::uint64_t>(count) > most) return false;
  std::vector<hsize_t> extent(static_cast<std::size_t>(rank));
  if (rank > 0) H5Sget_simple_extent_dims(space.get(), extent.data(), nullptr);
  dims.assign(extent.begin(), extent.end());
  values.assign(static_cast<std::size_t>(count), 0.0);
  return count == 0 || H5Aread(attr.get(), H5T_NATIVE_DOUBLE, values.data()) >= 0;
}

template bool Hdf5Reader::read(const std::string&, std::vector<double>&) const;
template bool Hdf5Reader::read(const std::string&, std::vector<std::int64_t>&) const;
template bool Hdf5Reader::read(const std::string&, std::vector<std::uint64_t>&) const;

}  // namespace glaswave
