#include "colmap_io/ply.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iomanip>
#include <limits>
#include <ostream>
#include <sstream>
#include <vector>

#include "util/error.h"
#include "util/file.h"
#include "util/logging.h"

namespace mr {
namespace {

enum class ScalarType { kInt8, kUInt8, kInt16, kUInt16, kInt32, kUInt32, kFloat32, kFloat64 };

bool ParseScalarType(const std::string& name, ScalarType* type) {
  static const struct {
    const char* name;
    ScalarType type;
  } kTypes[] = {
      {"char", ScalarType::kInt8},      {"int8", ScalarType::kInt8},
      {"uchar", ScalarType::kUInt8},    {"uint8", ScalarType::kUInt8},
      {"short", ScalarType::kInt16},    {"int16", ScalarType::kInt16},
      {"ushort", ScalarType::kUInt16},  {"uint16", ScalarType::kUInt16},
      {"int", ScalarType::kInt32},      {"int32", ScalarType::kInt32},
      {"uint", ScalarType::kUInt32},    {"uint32", ScalarType::kUInt32},
      {"float", ScalarType::kFloat32},  {"float32", ScalarType::kFloat32},
      {"double", ScalarType::kFloat64}, {"float64", ScalarType::kFloat64},
  };
  for (const auto& t : kTypes) {
    if (name == t.name) {
      *type = t.type;
      return true;
    }
  }
  return false;
}

int ScalarSize(ScalarType type) {
  switch (type) {
    case ScalarType::kInt8:
    case ScalarType::kUInt8:
      return 1;
    case ScalarType::kInt16:
    case ScalarType::kUInt16:
      return 2;
    case ScalarType::kInt32:
    case ScalarType::kUInt32:
    case ScalarType::kFloat32:
      return 4;
    case ScalarType::kFloat64:
      return 8;
  }
  return 0;
}

bool IsIntegerType(ScalarType type) {
  return type != ScalarType::kFloat32 && type != ScalarType::kFloat64;
}

struct Property {
  std::string name;
  ScalarType type = ScalarType::kFloat32;
  bool is_list = false;
  ScalarType count_type = ScalarType::kUInt8;
};

struct Element {
  std::string name;
  int64_t count = 0;
  std::vector<Property> properties;
  // Byte size of one record if no property is a list, else -1.
  int64_t FixedSize() const {
    int64_t size = 0;
    for (const Property& p : properties) {
      if (p.is_list) return -1;
      size += ScalarSize(p.type);
    }
    return size;
  }
  int Find(const std::string& property_name) const {
    for (size_t i = 0; i < properties.size(); ++i) {
      if (properties[i].name == property_name) return static_cast<int>(i);
    }
    return -1;
  }
};

template <typename T>
T LoadRaw(const char* p, bool swap) {
  T value;
  if (swap) {
    char bytes[sizeof(T)];
    for (size_t i = 0; i < sizeof(T); ++i) bytes[i] = p[sizeof(T) - 1 - i];
    std::memcpy(&value, bytes, sizeof(T));
  } else {
    std::memcpy(&value, p, sizeof(T));
  }
  return value;
}

double LoadScalar(const char* p, ScalarType type, bool swap) {
  switch (type) {
    case ScalarType::kInt8:
      return LoadRaw<int8_t>(p, false);
    case ScalarType::kUInt8:
      return LoadRaw<uint8_t>(p, false);
    case ScalarType::kInt16:
      return LoadRaw<int16_t>(p, swap);
    case ScalarType::kUInt16:
      return LoadRaw<uint16_t>(p, swap);
    case ScalarType::kInt32:
      return LoadRaw<int32_t>(p, swap);
    case ScalarType::kUInt32:
      return LoadRaw<uint32_t>(p, swap);
    case ScalarType::kFloat32:
      return LoadRaw<float>(p, swap);
    case ScalarType::kFloat64:
      return LoadRaw<double>(p, swap);
  }
  return 0;
}

bool HostIsLittleEndian() {
  const uint16_t one = 1;
  char byte;
  std::memcpy(&byte, &one, 1);
  return byte == 1;
}

// Reads the body value by value, either binary (with byte swapping) or ASCII.
class BodyReader {
 public:
  BodyReader(const std::string& path, const std::string& data, size_t offset, PlyFormat format)
      : path_(path),
        begin_(data.data()),
        pos_(data.data() + offset),
        end_(data.data() + data.size()),
        format_(format),
        swap_((format == PlyFormat::kBinaryBigEndian) == HostIsLittleEndian()) {}

  bool binary() const { return format_ != PlyFormat::kAscii; }
  // Byte offset of the next value in the file.
  size_t offset() const { return static_cast<size_t>(pos_ - begin_); }
  // ASCII: only blanks are left on the current line (records end lines).
  bool AtLineEnd() const {
    const char* p = pos_;
    while (p != end_ && (*p == ' ' || *p == '\t' || *p == '\r')) ++p;
    return p == end_ || *p == '\n';
  }

  // Reads one scalar of `type`; `what` names it in errors.
  double Read(ScalarType type, const Element& element, int64_t record) {
    if (binary()) {
      const int size = ScalarSize(type);
      if (end_ - pos_ < size) Truncated(element, record);
      const double value = LoadScalar(pos_, type, swap_);
      pos_ += size;
      return value;
    }
    return ReadAscii(type, element, record);
  }

  // Binary only: makes sure `bytes` more bytes exist, returns the current
  // pointer and advances past them.
  const char* Take(int64_t bytes, const Element& element, int64_t record) {
    if (end_ - pos_ < bytes) Truncated(element, record);
    const char* p = pos_;
    pos_ += bytes;
    return p;
  }

  bool swap() const { return swap_; }

  // Reads the length of a list (count of `type`). Every item takes at least
  // one byte (binary) or character (ASCII), so a length beyond the rest of
  // the file is refused before any loop or conversion to an integer.
  int64_t ReadListLength(ScalarType type, const Element& element, int64_t record) {
    const double n = Read(type, element, record);
    if (n < 0) {
      MR_THROW_INPUT << path_ << ": negative list length " << n << " in element '"
                     << element.name << "' record " << record;
    }
    if (n > static_cast<double>(end_ - pos_)) {
      MR_THROW_INPUT << path_ << ": truncated PLY body: element '" << element.name << "' record "
                     << record << " has a list of " << std::setprecision(15) << n
                     << " values but only " << (end_ - pos_)
                     << (binary() ? " bytes" : " characters") << " are left";
    }
    return static_cast<int64_t>(n);
  }

  // Bytes (binary) or non-space characters (ASCII) left after the body.
  bool HasTrailingData() const {
    if (binary()) return pos_ != end_;
    for (const char* p = pos_; p != end_; ++p) {
      if (!std::isspace(static_cast<unsigned char>(*p))) return true;
    }
    return false;
  }

 private:
  [[noreturn]] void Truncated(const Element& element, int64_t record) const {
    MR_THROW_INPUT << path_ << ": truncated PLY body: element '" << element.name << "' record "
                   << record << " of " << element.count << " ends past the end of the file ("
                   << (end_ - begin_) << " bytes)";
  }

  double ReadAscii(ScalarType type, const Element& element, int64_t record) {
    while (pos_ != end_ && std::isspace(static_cast<unsigned char>(*pos_))) ++pos_;
    if (pos_ == end_) Truncated(element, record);
    const char* token_end = pos_;
    while (token_end != end_ && !std::isspace(static_cast<unsigned char>(*token_end))) {
      ++token_end;
    }
    token_.assign(pos_, token_end);
    char* parse_end = nullptr;
    const double value = std::strtod(token_.c_str(), &parse_end);
    if (parse_end != token_.c_str() + token_.size() || token_.empty()) {
      MR_THROW_INPUT << path_ << ": invalid number '" << token_ << "' in element '"
                     << element.name << "' record " << record;
    }
    if (IsIntegerType(type) && value != std::floor(value)) {
      MR_THROW_INPUT << path_ << ": non-integer value '" << token_
                     << "' for an integer property in element '" << element.name << "' record "
                     << record;
    }
    pos_ = token_end;
    // A float property holds a float: round like a binary file would.
    if (type == ScalarType::kFloat32) return static_cast<double>(static_cast<float>(value));
    return value;
  }

  const std::string& path_;
  const char* begin_;
  const char* pos_;
  const char* end_;
  PlyFormat format_;
  bool swap_;
  std::string token_;
};

struct Header {
  PlyFormat format = PlyFormat::kAscii;
  std::vector<Element> elements;
  size_t body_offset = 0;
};

Header ParseHeader(const std::string& path, const std::string& data) {
  Header header;
  if (data.compare(0, 3, "ply") != 0 ||
      (data.size() > 3 && data[3] != '\n' && data[3] != '\r')) {
    MR_THROW_INPUT << path << ": not a PLY file (the first line is not 'ply')";
  }
  size_t pos = 0;
  int line_number = 0;
  bool have_format = false;
  bool have_end = false;
  while (pos < data.size()) {
    size_t eol = data.find('\n', pos);
    if (eol == std::string::npos) break;
    std::string line = data.substr(pos, eol - pos);
    pos = eol + 1;
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line_number == 1) continue;  // "ply"
    std::istringstream in(line);
    std::string keyword;
    in >> keyword;
    if (keyword.empty() || keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "end_header") {
      have_end = true;
      break;
    }
    if (keyword == "format") {
      std::string name, version;
      in >> name >> version;
      if (name == "binary_little_endian") {
        header.format = PlyFormat::kBinaryLittleEndian;
      } else if (name == "binary_big_endian") {
        header.format = PlyFormat::kBinaryBigEndian;
      } else if (name == "ascii") {
        header.format = PlyFormat::kAscii;
      } else {
        MR_THROW_INPUT << path << ": unknown PLY format '" << name << "' on header line "
                       << line_number
                       << " (expected ascii, binary_little_endian or binary_big_endian)";
      }
      if (version != "1.0") {
        MR_THROW_INPUT << path << ": unsupported PLY version '" << version << "' (expected 1.0)";
      }
      have_format = true;
    } else if (keyword == "element") {
      Element element;
      std::string count;
      in >> element.name >> count;
      char* end = nullptr;
      errno = 0;
      const long long n = std::strtoll(count.c_str(), &end, 10);
      if (element.name.empty() || count.empty() || *end != '\0' || n < 0 || errno == ERANGE) {
        MR_THROW_INPUT << path << ": malformed element line " << line_number << ": '" << line
                       << "' (expected 'element <name> <count>')";
      }
      element.count = n;
      header.elements.push_back(element);
    } else if (keyword == "property") {
      if (header.elements.empty()) {
        MR_THROW_INPUT << path << ": property before any element on header line " << line_number;
      }
      Property property;
      std::string type;
      in >> type;
      if (type == "list") {
        std::string count_type, item_type;
        in >> count_type >> item_type >> property.name;
        property.is_list = true;
        if (!ParseScalarType(count_type, &property.count_type) ||
            !ParseScalarType(item_type, &property.type)) {
          MR_THROW_INPUT << path << ": unknown type in list property on header line "
                         << line_number << ": '" << line << "'";
        }
        if (!IsIntegerType(property.count_type)) {
          MR_THROW_INPUT << path << ": list count type must be an integer type on header line "
                         << line_number << ": '" << line << "'";
        }
      } else {
        in >> property.name;
        if (!ParseScalarType(type, &property.type)) {
          MR_THROW_INPUT << path << ": unknown property type '" << type << "' on header line "
                         << line_number;
        }
      }
      if (property.name.empty()) {
        MR_THROW_INPUT << path << ": property without a name on header line " << line_number;
      }
      header.elements.back().properties.push_back(property);
    } else {
      MR_THROW_INPUT << path << ": unknown PLY header keyword '" << keyword << "' on line "
                     << line_number;
    }
  }
  if (!have_end) {
    MR_THROW_INPUT << path << ": truncated PLY header (no 'end_header' line)";
  }
  if (!have_format) MR_THROW_INPUT << path << ": PLY header has no 'format' line";
  header.body_offset = pos;
  return header;
}

// Scalar property indices of interest within the vertex element (-1: absent).
struct VertexLayout {
  int x = -1, y = -1, z = -1;
  int nx = -1, ny = -1, nz = -1;
  int red = -1, green = -1, blue = -1;
  int value = -1;
};

bool IsScalar(const Element& element, int index) {
  return index >= 0 && !element.properties[index].is_list;
}

void CheckFinite(const std::string& path, double v, int64_t record, const char* name) {
  if (!std::isfinite(v)) {
    MR_THROW_INPUT << path << ": vertex " << record << " has a non-finite " << name << " (" << v
                   << ")";
  }
}

uint8_t ToColor(double v, ScalarType type) {
  if (!IsIntegerType(type)) v *= 255.0;  // float colours are in [0, 1]
  if (!(v >= 0)) return 0;  // also NaN
  if (v > 255) return 255;
  return static_cast<uint8_t>(std::lround(v));
}

// Binary files whose face element failed to read: the number of vertices
// after which the faces would read exactly to the end of the file, when that
// is fewer than the header claims (the header overstates the vertex count);
// else -1. Only for the common layout: fixed-size vertex records directly
// followed by the last element, faces with the index list as only property.
int64_t VerticesBeforeFaces(const std::string& data, const Header& header, int vertex_element,
                            int face_element, int face_list, size_t face_begin, bool swap) {
  const Element& vertex = header.elements[vertex_element];
  const Element& face = header.elements[face_element];
  const int64_t vertex_size = vertex.FixedSize();
  if (vertex_size <= 0 || face_element != vertex_element + 1 ||
      face_element + 1 != static_cast<int>(header.elements.size()) ||
      face.properties.size() != 1 || face_list != 0) {
    return -1;
  }
  const int count_size = ScalarSize(face.properties[0].count_type);
  const int index_size = ScalarSize(face.properties[0].type);
  const ScalarType count_type = face.properties[0].count_type, index_type = face.properties[0].type;
  const char* end = data.data() + data.size();
  int64_t budget = 4 * face.count + (int64_t(1) << 24);  // faces walked in all
  for (int64_t missing = 1; missing <= vertex.count && budget > 0; ++missing) {
    const int64_t held = vertex.count - missing;
    const char* p = data.data() + face_begin - missing * vertex_size;
    bool ok = true;
    for (int64_t f = 0; ok && f < face.count; ++f, --budget) {
      if (end - p < count_size) {
        ok = false;
        break;
      }
      const double n = LoadScalar(p, count_type, swap);
      p += count_size;
      if (n < 3 || (end - p) / index_size < n) {
        ok = false;
        break;
      }
      for (int64_t j = 0; j < static_cast<int64_t>(n); ++j, p += index_size) {
        const double index = LoadScalar(p, index_type, swap);
        if (index < 0 || index >= static_cast<double>(held)) {
          ok = false;
          break;
        }
      }
    }
    if (ok && p == end) return held;
  }
  return -1;
}

}  // namespace

TriangleMesh ReadPly(const std::string& path) { return ReadPlyData(path, ReadFileToString(path)); }

TriangleMesh ReadPlyData(const std::string& path, const std::string& data) {
  const Header header = ParseHeader(path, data);

  int vertex_element = -1;
  int face_element = -1;
  for (size_t i = 0; i < header.elements.size(); ++i) {
    const std::string& name = header.elements[i].name;
    if (name == "vertex" && vertex_element < 0) vertex_element = static_cast<int>(i);
    if (name == "face" && face_element < 0) face_element = static_cast<int>(i);
  }
  if (vertex_element < 0) MR_THROW_INPUT << path << ": PLY file has no 'vertex' element";

  const Element& vertex = header.elements[vertex_element];
  VertexLayout layout;
  layout.x = vertex.Find("x");
  layout.y = vertex.Find("y");
  layout.z = vertex.Find("z");
  if (!IsScalar(vertex, layout.x) || !IsScalar(vertex, layout.y) || !IsScalar(vertex, layout.z)) {
    MR_THROW_INPUT << path << ": the vertex element lacks a scalar x, y or z property";
  }
  layout.nx = vertex.Find("nx");
  layout.ny = vertex.Find("ny");
  layout.nz = vertex.Find("nz");
  const bool has_normals =
      IsScalar(vertex, layout.nx) && IsScalar(vertex, layout.ny) && IsScalar(vertex, layout.nz);
  layout.red = vertex.Find("red");
  layout.green = vertex.Find("green");
  layout.blue = vertex.Find("blue");
  if (layout.red < 0 && layout.green < 0 && layout.blue < 0) {
    layout.red = vertex.Find("diffuse_red");
    layout.green = vertex.Find("diffuse_green");
    layout.blue = vertex.Find("diffuse_blue");
  }
  const bool has_colors = IsScalar(vertex, layout.red) && IsScalar(vertex, layout.green) &&
                          IsScalar(vertex, layout.blue);
  layout.value = vertex.Find("value");
  const bool has_values = IsScalar(vertex, layout.value);

  int face_list = -1;
  if (face_element >= 0) {
    const Element& face = header.elements[face_element];
    face_list = face.Find("vertex_indices");
    if (face_list < 0) face_list = face.Find("vertex_index");
    if (face_list < 0 || !face.properties[face_list].is_list) {
      MR_THROW_INPUT << path << ": the face element has no list property 'vertex_indices'";
    }
    if (!IsIntegerType(face.properties[face_list].type)) {
      MR_THROW_INPUT << path << ": face indices must have an integer type";
    }
  }
  if (vertex.count > std::numeric_limits<int>::max()) {
    MR_THROW_INPUT << path << ": too many vertices (" << vertex.count << ")";
  }

  // Fail fast on an obviously short body (before allocating for the counts
  // the header claims). ASCII values take at least two characters each (the
  // value and a separator; the file's last value may lack its newline).
  {
    const bool ascii = header.format == PlyFormat::kAscii;
    double min_size = ascii ? -1 : 0;
    const double available = static_cast<double>(data.size() - header.body_offset);
    std::string room;  // where the file must end, for the message
    for (const Element& element : header.elements) {
      double record = 0;
      for (const Property& p : element.properties) {
        record += ascii ? 2 : (p.is_list ? ScalarSize(p.count_type) : ScalarSize(p.type));
      }
      const double before = std::max(0.0, min_size);
      min_size += record * static_cast<double>(element.count);
      if (room.empty() && available < min_size && record > 0) {
        const int64_t fit = static_cast<int64_t>(std::max(0.0, (available - before) / record));
        room = "room for at most " + std::to_string(fit) + " of " +
               std::to_string(element.count) + " " + element.name + " records";
      }
    }
    if (available < min_size) {
      // min_size may exceed every integer type (counts up to 2^63 - 1).
      MR_THROW_INPUT << path << ": truncated PLY body: the header needs at least " << std::fixed
                     << std::setprecision(0) << min_size << (ascii ? " characters" : " bytes")
                     << " after the header, the file has " << data.size() - header.body_offset
                     << " (" << room << ")";
    }
  }

  TriangleMesh mesh;
  const int64_t num_vertices = vertex.count;
  mesh.V.resize(num_vertices, 3);
  if (has_normals) mesh.N.resize(num_vertices, 3);
  if (has_colors) mesh.C.resize(num_vertices, 3);
  if (has_values) mesh.values.resize(num_vertices);
  std::vector<int> triangles;


  BodyReader reader(path, data, header.body_offset, header.format);
  std::vector<double> record_values;
  // ASCII: the first vertex record that does not end its line (-1: none),
  // the sign of a header that claims more vertices than the file holds.
  int64_t first_unended_vertex = -1;
  for (size_t e = 0; e < header.elements.size(); ++e) {
    const Element& element = header.elements[e];
    const int64_t fixed_size = element.FixedSize();
    if (static_cast<int>(e) == vertex_element) {
      record_values.resize(element.properties.size());
      for (int64_t i = 0; i < element.count; ++i) {
        if (reader.binary() && fixed_size >= 0) {
          // Fast path: one bounds check per record.
          const char* p = reader.Take(fixed_size, element, i);
          for (size_t k = 0; k < element.properties.size(); ++k) {
            const ScalarType type = element.properties[k].type;
            record_values[k] = LoadScalar(p, type, reader.swap());
            p += ScalarSize(type);
          }
        } else {
          for (size_t k = 0; k < element.properties.size(); ++k) {
            const Property& prop = element.properties[k];
            if (prop.is_list) {
              const int64_t n = reader.ReadListLength(prop.count_type, element, i);
              for (int64_t j = 0; j < n; ++j) reader.Read(prop.type, element, i);
              record_values[k] = 0;
            } else {
              record_values[k] = reader.Read(prop.type, element, i);
            }
          }
        }
        const double x = record_values[layout.x], y = record_values[layout.y],
                     z = record_values[layout.z];
        CheckFinite(path, x, i, "x");
        CheckFinite(path, y, i, "y");
        CheckFinite(path, z, i, "z");
        mesh.V.row(i) << x, y, z;
        if (has_normals) {
          mesh.N.row(i) << record_values[layout.nx], record_values[layout.ny],
              record_values[layout.nz];
        }
        if (has_colors) {
          mesh.C(i, 0) = ToColor(record_values[layout.red], element.properties[layout.red].type);
          mesh.C(i, 1) =
              ToColor(record_values[layout.green], element.properties[layout.green].type);
          mesh.C(i, 2) = ToColor(record_values[layout.blue], element.properties[layout.blue].type);
        }
        if (has_values) mesh.values(i) = record_values[layout.value];
        if (!reader.binary() && first_unended_vertex < 0 && !reader.AtLineEnd()) {
          first_unended_vertex = i;
        }
      }
    } else if (static_cast<int>(e) == face_element) {
      triangles.reserve(element.count * 3);
      int corners[3];
      const size_t face_begin = reader.offset();
      try {
        for (int64_t i = 0; i < element.count; ++i) {
          for (size_t k = 0; k < element.properties.size(); ++k) {
            const Property& prop = element.properties[k];
            if (!prop.is_list) {
              reader.Read(prop.type, element, i);
              continue;
            }
            const int64_t n = reader.ReadListLength(prop.count_type, element, i);
            if (static_cast<int>(k) != face_list) {
              for (int64_t j = 0; j < n; ++j) reader.Read(prop.type, element, i);
              continue;
            }
            if (n < 3) {
              MR_THROW_INPUT << path << ": face " << i << " has " << n
                             << " corners (expected at least 3)";
            }
            for (int64_t j = 0; j < n; ++j) {
              const double index = reader.Read(prop.type, element, i);
              if (index < 0 || index >= static_cast<double>(num_vertices)) {
                MR_THROW_INPUT << path << ": face " << i << " has vertex index " << index
                               << " out of range [0, " << num_vertices << ")";
              }
              const int v = static_cast<int>(index);
              // Fan triangulation: (c0, c_{j-1}, c_j) for j >= 2.
              if (j < 2) {
                corners[j] = v;
              } else {
                corners[2] = v;
                triangles.insert(triangles.end(), corners, corners + 3);
                corners[1] = v;
              }
            }
          }
        }
      } catch (const InputError&) {
        // Faces that do not read may be faces read from the wrong place.
        int64_t held = -1;
        if (reader.binary()) {
          held = VerticesBeforeFaces(data, header, vertex_element, face_element, face_list,
                                     face_begin, reader.swap());
        } else if (static_cast<int>(e) == vertex_element + 1) {
          held = first_unended_vertex;
        }
        if (held >= 0) {
          MR_THROW_INPUT << path << ": the header claims more vertices than the file holds: "
                         << "the vertices end after vertex " << held << " of " << vertex.count
                         << " and the " << element.count << " faces follow";
        }
        throw;
      }
    } else {
      // Skip an element we do not use.
      if (reader.binary() && fixed_size >= 0) {
        if (fixed_size > 0 && element.count > 0) {
          reader.Take(fixed_size * element.count, element, element.count - 1);
        }
        continue;
      }
      if (element.properties.empty()) continue;  // nothing to read, however many records
      for (int64_t i = 0; i < element.count; ++i) {
        for (const Property& prop : element.properties) {
          if (prop.is_list) {
            const int64_t n = reader.ReadListLength(prop.count_type, element, i);
            for (int64_t j = 0; j < n; ++j) reader.Read(prop.type, element, i);
          } else {
            reader.Read(prop.type, element, i);
          }
        }
      }
    }
  }

  if (reader.HasTrailingData()) {
    MR_LOG(WARNING) << path << ": ignoring data after the last PLY element";
  }
  mesh.F.resize(static_cast<Eigen::Index>(triangles.size() / 3), 3);
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
    mesh.F(f, 0) = triangles[3 * f];
    mesh.F(f, 1) = triangles[3 * f + 1];
    mesh.F(f, 2) = triangles[3 * f + 2];
  }
  return mesh;
}

namespace {

template <typename T>
void Append(std::string* buffer, T value, bool big_endian) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if (big_endian == HostIsLittleEndian()) std::reverse(bytes, bytes + sizeof(T));
  buffer->append(bytes, sizeof(T));
}

void AppendAscii(std::string* buffer, float value) {
  char text[32];
  const int n = std::snprintf(text, sizeof(text), "%.9g", static_cast<double>(value));
  buffer->append(text, n);
}

}  // namespace

void WritePly(const std::string& path, const TriangleMesh& mesh, PlyFormat format) {
  const Eigen::Index nv = mesh.V.rows();
  MR_CHECK(mesh.V.cols() == 3 || nv == 0) << path << ": V must be #V by 3";
  MR_CHECK(mesh.F.rows() == 0 || mesh.F.cols() == 3) << path << ": F must be #F by 3";
  const bool has_normals = mesh.N.size() > 0;
  const bool has_colors = mesh.C.size() > 0;
  const bool has_values = mesh.values.size() > 0;
  MR_CHECK(!has_normals || (mesh.N.rows() == nv && mesh.N.cols() == 3)) << path;
  MR_CHECK(!has_colors || mesh.C.rows() == nv) << path;
  MR_CHECK(!has_values || mesh.values.size() == nv) << path;
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      MR_CHECK(mesh.F(f, k) >= 0 && mesh.F(f, k) < nv)
          << path << ": face " << f << " has vertex index " << mesh.F(f, k) << " of " << nv;
    }
  }

  std::ostringstream header;
  header << "ply\n";
  switch (format) {
    case PlyFormat::kBinaryLittleEndian:
      header << "format binary_little_endian 1.0\n";
      break;
    case PlyFormat::kBinaryBigEndian:
      header << "format binary_big_endian 1.0\n";
      break;
    case PlyFormat::kAscii:
      header << "format ascii 1.0\n";
      break;
  }
  header << "comment written by mesh_refiner\n";
  header << "element vertex " << nv << "\n";
  header << "property float x\nproperty float y\nproperty float z\n";
  if (has_normals) header << "property float nx\nproperty float ny\nproperty float nz\n";
  if (has_colors) header << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  if (has_values) header << "property float value\n";
  if (mesh.F.rows() > 0) {
    header << "element face " << mesh.F.rows() << "\n";
    header << "property list uchar int vertex_indices\n";
  }
  header << "end_header\n";

  std::string body;
  if (format == PlyFormat::kAscii) {
    body.reserve(nv * 40 + mesh.F.rows() * 24);
    for (Eigen::Index i = 0; i < nv; ++i) {
      for (int k = 0; k < 3; ++k) {
        if (k > 0) body += ' ';
        AppendAscii(&body, static_cast<float>(mesh.V(i, k)));
      }
      if (has_normals) {
        for (int k = 0; k < 3; ++k) {
          body += ' ';
          AppendAscii(&body, static_cast<float>(mesh.N(i, k)));
        }
      }
      if (has_colors) {
        for (int k = 0; k < 3; ++k) body += ' ' + std::to_string(int(mesh.C(i, k)));
      }
      if (has_values) {
        body += ' ';
        AppendAscii(&body, static_cast<float>(mesh.values(i)));
      }
      body += '\n';
    }
    for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
      body += "3 " + std::to_string(mesh.F(f, 0)) + ' ' + std::to_string(mesh.F(f, 1)) + ' ' +
              std::to_string(mesh.F(f, 2)) + '\n';
    }
  } else {
    const bool big = format == PlyFormat::kBinaryBigEndian;
    const size_t vertex_size =
        12 + (has_normals ? 12 : 0) + (has_colors ? 3 : 0) + (has_values ? 4 : 0);
    body.reserve(nv * vertex_size + mesh.F.rows() * 13);
    for (Eigen::Index i = 0; i < nv; ++i) {
      for (int k = 0; k < 3; ++k) Append(&body, static_cast<float>(mesh.V(i, k)), big);
      if (has_normals) {
        for (int k = 0; k < 3; ++k) Append(&body, static_cast<float>(mesh.N(i, k)), big);
      }
      if (has_colors) {
        for (int k = 0; k < 3; ++k) body += static_cast<char>(mesh.C(i, k));
      }
      if (has_values) Append(&body, static_cast<float>(mesh.values(i)), big);
    }
    for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
      body += static_cast<char>(3);
      for (int k = 0; k < 3; ++k) Append(&body, static_cast<int32_t>(mesh.F(f, k)), big);
    }
  }

  WriteFileAtomically(path, [&](std::ostream& out) {
    const std::string h = header.str();
    out.write(h.data(), static_cast<std::streamsize>(h.size()));
    out.write(body.data(), static_cast<std::streamsize>(body.size()));
  });
}

}  // namespace mr
