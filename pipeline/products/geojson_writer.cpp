// footprints.geojson, written by hand rather than through OGR: the format is small, and
// writing it directly keeps full control of what RFC 7946 and ogrinfo care about (no `crs`
// member, ring orientation kept as given, no NaN, coordinates to 1e-8 degree).
#include "pipeline/products/geojson_writer.hpp"

#include <array>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "pipeline/products/product_fields.hpp"

namespace glaswave {
namespace {

// 1e-8 degree is about a millimetre on the ground: finer than any footprint position means.
constexpr int kCoordinateDecimals = 8;

struct FileCloser {
  void operator()(std::FILE* file) const { std::fclose(file); }
};
using FilePtr = std::unique_ptr<std::FILE, FileCloser>;

// A coordinate with a fixed number of decimals, trailing zeros dropped.
void append_coordinate(std::string& out, double value) {
  std::array<char, 64> buffer{};
  const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value,
                                    std::chars_format::fixed, kCoordinateDecimals);
  std::string_view text(buffer.data(), result.ptr);
  while (text.ends_with('0')) text.remove_suffix(1);
  if (text.ends_with('.')) text.remove_suffix(1);
  if (text == "-0") text = "0";
  out += text;
}

// A JSON number that reads back to the same double, or null: JSON has no NaN. It always
// carries a '.' or an exponent so that OGR types the property as Real even when every shot
// has an integral value (a flat plane's slope).
void append_real(std::string& out, double value) {
  if (!std::isfinite(value)) {
    out += "null";
    return;
  }
  std::array<char, 64> buffer{};
  const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  const std::string_view text(buffer.data(), result.ptr);
  out += text;
  if (text.find_first_of(".e") == std::string_view::npos) out += ".0";
}

// Property `k` of `field` (product_fields.hpp): a scalar, or the first band's value of a
// per-band field, or its level kGeojsonLevels[k]; null where the shot has none (fill).
void append_property(std::string& out, const ShotRecord& shot, const ProductField& field,
                     std::size_t k) {
  std::visit(
      [&](auto member) {
        const auto& value = shot.*member;
        using T = std::remove_cvref_t<decltype(value)>;
        if constexpr (std::is_same_v<T, double>) {
          append_real(out, value);
        } else if constexpr (std::is_integral_v<T>) {
          out += std::to_string(static_cast<std::int64_t>(value));
        } else if constexpr (std::is_same_v<T, std::vector<double>>) {
          append_real(out, value.empty() ? std::nan("") : value.front());
        } else if constexpr (std::is_same_v<T, std::vector<std::int32_t>>) {
          out += value.empty() ? std::string("null") : std::to_string(value.front());
        } else if constexpr (std::is_same_v<T, std::vector<std::vector<double>>>) {
          const auto level = static_cast<std::size_t>(kGeojsonLevels[k]);
          const bool known = !value.empty() && value.front().size() > level;
          append_real(out, known ? value.front()[level] : std::nan(""));
        } else {
          out += "null";  // arrays over orders are never properties
        }
      },
      field.field);
}

using Ring = std::vector<std::array<double, 2>>;

// RFC 7946 section 3.1.9: a ring that crosses the antimeridian is cut there into two polygons,
// one each side, rather than drawn the long way round the globe. Longitudes are first made
// continuous from the first vertex; a ring that then stays within [-180, 180] is kept whole.
std::vector<Ring> split_at_antimeridian(const Ring& ring) {
  Ring continuous = ring;
  for (std::size_t i = 1; i < continuous.size(); ++i)
    continuous[i][0] = continuous[i - 1][0] + std::remainder(ring[i][0] - ring[i - 1][0], 360.0);
  double west = continuous[0][0], east = west;
  for (const auto& p : continuous) {
    west = std::min(west, p[0]);
    east = std::max(east, p[0]);
  }
  if (west >= -180.0 && east <= 180.0) return {ring};
  const double cut = east > 180.0 ? 180.0 : -180.0;
  // Sutherland-Hodgman against the meridian `cut`, keeping one side and then the other.
  auto clip = [&](bool keep_west) {
    Ring out;
    for (std::size_t i = 0; i + 1 < continuous.size(); ++i) {
      const auto& a = continuous[i];
      const auto& b = continuous[i + 1];
      const bool a_in = keep_west ? a[0] <= cut : a[0] >= cut,
                 b_in = keep_west ? b[0] <= cut : b[0] >= cut;
      if (a_in) out.push_back(a);
      if (a_in != b_in) out.push_back({cut, a[1] + (b[1] - a[1]) * (cut - a[0]) / (b[0] - a[0])});
    }
    if (out.size() >= 3) out.push_back(out.front());
    // Back into [-180, 180]: the part beyond the cut moves by a turn.
    const double shift = (keep_west == (cut > 0.0)) ? 0.0 : (cut > 0.0 ? -360.0 : 360.0);
    for (auto& p : out) p[0] += shift;
    return out;
  };
  std::vector<Ring> parts;
  for (bool keep_west : {true, false}) {
    Ring part = clip(keep_west);
    if (part.size() >= 4) parts.push_back(std::move(part));
  }
  return parts;
}

}  // namespace

struct GeojsonWriter::Impl {
  explicit Impl(std::filesystem::path final_path) : file(std::move(final_path)) {}

  // Declared before the stream so that it is destroyed after it: the file is closed before
  // an unfinished .part is removed.
  AtomicFile file;
  FilePtr out;
  std::int64_t shots = 0;
  std::int64_t next = 0;                        // the next record to go to the file
  std::map<std::int64_t, std::string> pending;  // records that came before their turn
  bool finished = false;

  [[noreturn]] void fail(const std::string& message) const {
    throw run_error(file.final_path().string(), message);
  }

  void put(const std::string& text) {
    if (std::fwrite(text.data(), 1, text.size(), out.get()) != text.size()) {
      fail(std::string("cannot write ") + file.part_path().string() + ": " + std::strerror(errno));
    }
  }

  // The geometry member's value: the footprint as a Polygon (a MultiPolygon where it crosses
  // the antimeridian), or null for a shot without one.
  void append_geometry(std::string& text, std::int64_t index, const ShotRecord& shot) const {
    const auto& ring = shot.footprint_lonlat;
    if (ring.empty()) {
      text += "null";
      return;
    }
    const std::string place = "footprint ring of record " + std::to_string(index) + " (shot " +
                              std::to_string(shot.shot_number) + ")";
    if (ring.size() < 4 || ring.front() != ring.back()) {
      fail(place + ": a Polygon ring must be closed with at least 4 positions, got " +
           std::to_string(ring.size()));
    }
    for (std::size_t i = 0; i < ring.size(); ++i)
      if (!std::isfinite(ring[i][0]) || !std::isfinite(ring[i][1]))
        fail(place + ": position " + std::to_string(i) + " is not finite");
    const std::vector<Ring> parts = split_at_antimeridian(ring);
    text += parts.size() == 1 ? R"({"type":"Polygon","coordinates":)"
                              : R"({"type":"MultiPolygon","coordinates":[)";
    for (std::size_t p = 0; p < parts.size(); ++p) {
      text += p == 0 ? "[[" : ",[[";
      for (std::size_t i = 0; i < parts[p].size(); ++i) {
        text += i == 0 ? "[" : ",[";
        append_coordinate(text, parts[p][i][0]);
        text += ',';
        append_coordinate(text, parts[p][i][1]);
        text += ']';
      }
      text += "]]";
    }
    text += parts.size() == 1 ? "}" : "]}";
  }

  std::string feature(std::int64_t index, const ShotRecord& shot) const {
    std::string text = R"({"type":"Feature","geometry":)";
    append_geometry(text, index, shot);
    text += R"(,"properties":{)";
    bool first = true;
    for (const ProductField& field : product_fields()) {
      if (field.geojson == GeojsonProperty::none) continue;
      const std::vector<std::string> names = geojson_property_names(field);
      for (std::size_t k = 0; k < names.size(); ++k) {
        text += first ? "\"" : ",\"";
        text += names[k];
        text += "\":";
        append_property(text, shot, field, k);
        first = false;
      }
    }
    text += "}}";
    return text;
  }

  void emit(const std::string& feature_text) {
    put(next == 0 ? feature_text : ",\n" + feature_text);
    ++next;
  }
};

GeojsonWriter::GeojsonWriter(std::filesystem::path final_path, const RunInfo& info)
    : final_path_(std::move(final_path)), impl_(std::make_unique<Impl>(final_path_)) {
  Impl& impl = *impl_;
  if (info.shots < 1)
    impl.fail("a product needs at least one shot, got " + std::to_string(info.shots));
  impl.shots = info.shots;
  impl.out.reset(std::fopen(impl.file.part_path().c_str(), "wb"));
  if (!impl.out)
    impl.fail("cannot create " + impl.file.part_path().string() + ": " + std::strerror(errno));
  impl.put("{\"type\":\"FeatureCollection\",\"features\":[\n");
}

GeojsonWriter::~GeojsonWriter() = default;

GeojsonWriter::Impl& GeojsonWriter::impl() {
  if (!impl_) throw run_error(final_path_.string(), "the product was aborted");
  return *impl_;
}

void GeojsonWriter::write(std::int64_t index, const ShotRecord& shot) {
  Impl& impl = this->impl();
  if (impl.finished) impl.fail("write after finish");
  if (index < 0 || index >= impl.shots) {
    impl.fail("record index " + std::to_string(index) + " outside [0, " +
              std::to_string(impl.shots) + ")");
  }
  if (index < impl.next || impl.pending.contains(index))
    impl.fail("record " + std::to_string(index) + " written twice");
  std::string text = impl.feature(index, shot);
  if (index != impl.next) {
    impl.pending.emplace(index, std::move(text));
    return;
  }
  impl.emit(text);
  for (auto it = impl.pending.begin(); it != impl.pending.end() && it->first == impl.next;) {
    impl.emit(it->second);
    it = impl.pending.erase(it);
  }
}

void GeojsonWriter::finish(const RunStats& /*stats*/) {
  Impl& impl = this->impl();
  if (impl.finished) impl.fail("finished twice");
  if (impl.next != impl.shots)
    impl.fail("record " + std::to_string(impl.next) + " was never written");
  impl.put("\n]}\n");
  // fclose flushes: a full disk shows up here, not in fwrite.
  const int status = std::fclose(impl.out.release());
  if (status != 0)
    impl.fail("cannot write " + impl.file.part_path().string() + ": " + std::strerror(errno));
  impl.file.commit();
  impl.finished = true;
}

void GeojsonWriter::abort() noexcept {
  // A finished product stays: only an unfinished one has a .part to give up.
  if (impl_ && !impl_->finished) impl_.reset();
}

}  // namespace glaswave
