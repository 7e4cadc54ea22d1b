// What GDAL may open: /vsi prefixes sorted into streams (refused), wrappers of a local file (the
// file checked) and the rest (left to GDAL: memory, remote stores); VRTs read with CPL's XML
// parser for their sources.
#include "terrain/gdal_source.hpp"

#include <cpl_conv.h>
#include <cpl_minixml.h>
#include <cpl_string.h>
#include <cpl_vsi.h>
#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <memory>
#include <string_view>
#include <vector>

#include "core/input_file.hpp"

namespace glaswave {
namespace {

// Deeper VRT nesting than this is refused (a VRT naming itself would never end).
constexpr int kMaxDepth = 8;
// A VRT larger than this is not read here for its sources (GDAL reads it).
constexpr vsi_l_offset kMaxVrtBytes = 16 << 20;

bool starts_with(std::string_view text, std::string_view prefix) {
  return text.substr(0, prefix.size()) == prefix;
}

// The local file a wrapper's rest of path names: the longest leading part that is not a
// directory ("/data/a.zip" of "/data/a.zip/dem.tif"); empty when none exists.
std::string local_file_of(const std::string& rest) {
  for (std::size_t end = rest.find('/', 1);; end = rest.find('/', end + 1)) {
    const std::string part = rest.substr(0, end);
    struct stat status {};
    if (::stat(part.c_str(), &status) == 0 && !S_ISDIR(status.st_mode)) return part;
    if (end == std::string::npos) return {};
  }
}

// `chain`: the VRTs being read, from the one the user gave to the one naming `path`.
using VrtChain = std::vector<std::string>;
void check(const std::string& path, const std::string& what, ErrorKind kind, VrtChain& chain);

// A /vsi path: a stream is refused, a wrapped local file checked.
void check_vsi(const std::string& path, const std::string& what, ErrorKind kind, VrtChain& chain) {
  const std::size_t slash = path.find('/', 1);
  const std::string prefix = path.substr(0, slash == std::string::npos ? path.size() : slash + 1);
  if (prefix == "/vsistdin/" || prefix == "/vsistdin" || starts_with(prefix, "/vsistdout") ||
      prefix.find("_streaming") != std::string::npos)
    throw Error(kind, printable_path(path),
                "cannot read " + what + " from " + prefix +
                    ", a stream that GDAL would wait on: give a file (or /vsizip/, /vsimem/ ...)");
  std::string rest = slash == std::string::npos ? std::string() : path.substr(slash + 1);
  static constexpr std::array<std::string_view, 6> wrappers = {
      "/vsizip/", "/vsigzip/", "/vsitar/", "/vsi7z/", "/vsirar/", "/vsisubfile/"};
  bool wrapper = false;
  for (const std::string_view w : wrappers) wrapper = wrapper || prefix == w;
  if (!wrapper) return;            // GDAL's memory or a remote store: nothing local to wait on
  if (prefix == "/vsisubfile/") {  // /vsisubfile/OFFSET[_SIZE],FILE
    const std::size_t comma = rest.find(',');
    rest = comma == std::string::npos ? std::string() : rest.substr(comma + 1);
  }
  if (!rest.empty() && rest.front() == '{') {  // /vsizip/{archive}/member
    const std::size_t close = rest.find('}');
    rest = rest.substr(1, close == std::string::npos ? std::string::npos : close - 1);
  }
  if (!rest.empty() && rest.front() != '/') rest = "/" + rest;  // /vsizip/ takes "/" as a root
  if (starts_with(rest, "/vsi")) return check(rest, what, kind, chain);
  const std::string file = local_file_of(rest);
  if (!file.empty()) require_input_file(file, what, kind);
}

// A VRT's source files, checked before GDAL opens the VRT (which may open them at once).
void check_vrt_sources(const std::string& vrt, const std::string& what, ErrorKind kind,
                       VrtChain& chain) {
  VSIStatBufL status{};
  if (VSIStatL(vrt.c_str(), &status) != 0 ||
      static_cast<vsi_l_offset>(status.st_size) > kMaxVrtBytes)
    return;
  VSILFILE* file = VSIFOpenL(vrt.c_str(), "rb");
  if (!file) return;
  std::string text(static_cast<std::size_t>(status.st_size), '\0');
  text.resize(VSIFReadL(text.data(), 1, text.size(), file));
  VSIFCloseL(file);
  const std::size_t start = text.find_first_not_of(" \t\r\n\xef\xbb\xbf");
  if (start == std::string::npos || !(text.compare(start, 11, "<VRTDataset") == 0 ||
                                      text.compare(start, 17, "<OGRVRTDataSource") == 0))
    return;
  const std::unique_ptr<CPLXMLNode, void (*)(CPLXMLNode*)> root(CPLParseXMLString(text.c_str()),
                                                                CPLDestroyXMLNode);
  if (!root) return;  // GDAL says what is wrong with it
  const std::string folder = CPLGetPath(vrt.c_str());
  // A source's "what" says once that it is a VRT's source, however deep.
  constexpr std::string_view kSource = "'s VRT source";
  const std::string source_what =
      std::string_view(what).ends_with(kSource) ? what : what + std::string(kSource);
  chain.push_back(std::filesystem::path(vrt).lexically_normal().string());
  // Every element that names a source file, wherever it is (sources, overviews, masks).
  const auto visit = [&](const auto& self, const CPLXMLNode* node) -> void {
    for (; node; node = node->psNext) {
      if (node->eType != CXT_Element) continue;
      const std::string_view name = node->pszValue;
      if (name == "SourceFilename" || name == "SrcDataSource") {
        std::string source = CPLGetXMLValue(node, nullptr, "");
        const bool relative = CPLTestBool(CPLGetXMLValue(node, "relativeToVRT", "0")) ||
                              CPLTestBool(CPLGetXMLValue(node, "relativetoVRT", "0"));
        if (starts_with(source, "vrt://")) source = source.substr(6, source.find('?') - 6);
        if (relative && !source.empty() && source.front() != '/')
          source = CPLFormFilename(folder.c_str(), source.c_str(), nullptr);
        if (!source.empty()) check(source, source_what, kind, chain);
      }
      self(self, node->psChild);
    }
  };
  visit(visit, root.get());
  chain.pop_back();
}

void check(const std::string& path, const std::string& what, ErrorKind kind, VrtChain& chain) {
  // Named at the file the user gave, with the VRTs that lead there.
  const auto through = [&](const std::string& last) {
    std::string text;
    for (const std::string& vrt : chain)
      text += std::filesystem::path(vrt).filename().string() + " -> ";
    return text + std::filesystem::path(last).filename().string();
  };
  const std::string normal = std::filesystem::path(path).lexically_normal().string();
  if (std::find(chain.begin(), chain.end(), normal) != chain.end())
    throw Error(kind, printable_path(chain.front()),
                "cannot read " + what + ": its VRTs source each other (" + through(path) + ")");
  if (static_cast<int>(chain.size()) > kMaxDepth)
    throw Error(kind, printable_path(chain.front()),
                "cannot read " + what + ": VRTs nested deeper than " + std::to_string(kMaxDepth) +
                    " (" + through(path) + ")");
  require_no_nul(path, printable_path(path), kind);
  if (starts_with(path, "/vsi")) {
    check_vsi(path, what, kind, chain);
  } else {
    // "NETCDF:file.nc:var" and the like: the file is the part after the driver's name.
    std::string file = path;
    struct stat status {};
    const std::size_t colon = path.find(':');
    if (::stat(path.c_str(), &status) != 0 && colon != std::string::npos && colon > 1) {
      file = path.substr(colon + 1);
      if (!file.empty() && file.front() == '"')
        file = file.substr(1, file.find('"', 1) - 1);
      else
        file = file.substr(0, file.find(':'));
    }
    require_input_file(file, what, kind);
  }
  check_vrt_sources(path, what, kind, chain);
}

}  // namespace

void require_gdal_source(const std::string& path, const std::string& what, ErrorKind kind) {
  VrtChain chain;
  check(path, what, kind, chain);
}

}  // namespace glaswave
