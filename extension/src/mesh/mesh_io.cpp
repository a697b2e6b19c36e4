#include "torsion/mesh/mesh_io.h"

#include "torsion/device/file_io.h"
#include "torsion/mesh/gmsh_format.h"
#include "torsion/mesh/tetgen_format.h"
#include "torsion/mesh/vtk_format.h"

namespace torsion {

namespace fs = std::filesystem;

std::string lowerExtension(const fs::path& path) {
  std::string ext = path.extension().string();
  for (char& c : ext)
    c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

namespace {

// TetGen meshes are two files; any of "name", "name.node", "name.ele" names the pair.
struct TetGenPaths {
  fs::path node, ele;
};

TetGenPaths tetgenPaths(const fs::path& path) {
  fs::path base = path;
  const std::string ext = lowerExtension(path);
  if (ext == ".node" || ext == ".ele") base.replace_extension();
  TetGenPaths paths{base, base};
  paths.node += ".node";
  paths.ele += ".ele";
  return paths;
}

}  // namespace

Result<MeshFormat> meshFormatOf(const fs::path& path) {
  const std::string ext = lowerExtension(path);
  if (ext == ".node" || ext == ".ele") return MeshFormat::kTetGen;
  if (ext == ".msh") return MeshFormat::kGmsh;
  if (ext == ".vtk") return MeshFormat::kVtk;
  if (ext.empty()) {
    // error_code form: a name too long or a directory we may not search is "not found" here,
    // and the reader then reports the real reason instead of an exception aborting the program.
    std::error_code ec;
    if (fs::exists(tetgenPaths(path).node, ec)) return MeshFormat::kTetGen;
  }
  return Error{path.string() + ": unknown mesh format '" + ext +
               "' (known: .node/.ele for TetGen, .msh for Gmsh 2.2/4.1, .vtk for legacy VTK)"};
}

Result<std::string> readTextFile(const fs::path& path) {
  std::string content;
  if (std::string error = device::readRegularFile(path.string(), content); !error.empty())
    return Error{error};
  if (content.find_first_not_of(" \t\r\n") == std::string::npos) {
    return Error{path.string() + ": file is empty"};
  }
  return content;
}

Status writeTextFile(const fs::path& path, const std::string& text) {
  if (std::string error = device::writeFileAtomically(path.string(), text); !error.empty())
    return Error{error};
  return Ok{};
}

Result<LoadedMesh> readMesh(const fs::path& path, const MeshLoadOptions& options) {
  Result<MeshFormat> format = meshFormatOf(path);
  if (!format) return format.error();

  Result<RawTetMesh> raw = Error{};
  switch (format.value()) {
    case MeshFormat::kTetGen: {
      const TetGenPaths paths = tetgenPaths(path);
      Result<std::string> node_text = readTextFile(paths.node);
      if (!node_text) return node_text.error();
      Result<std::string> ele_text = readTextFile(paths.ele);
      if (!ele_text) return ele_text.error();
      raw =
          parseTetGen(node_text.value(), paths.node.string(), ele_text.value(), paths.ele.string());
      break;
    }
    case MeshFormat::kGmsh:
    case MeshFormat::kVtk: {
      Result<std::string> text = readTextFile(path);
      if (!text) return text.error();
      raw = format.value() == MeshFormat::kGmsh ? parseGmsh(text.value(), path.string())
                                                : parseVtk(text.value(), path.string());
      break;
    }
  }
  if (!raw) return raw.error();
  return buildTetMesh(std::move(raw).value(), options);
}

Status writeMesh(const fs::path& path, const TetMesh& mesh, const MeshFields& fields) {
  Result<MeshFormat> format = meshFormatOf(path);
  if (!format) return format.error();
  switch (format.value()) {
    case MeshFormat::kTetGen: {
      const TetGenPaths paths = tetgenPaths(path);
      // Both files or neither: a .node beside a stale .ele would be a different mesh.
      TetGenText text = formatTetGen(mesh);
      const std::string error = device::writeFilesTogether(
          {{paths.node.string(), std::move(text.node)}, {paths.ele.string(), std::move(text.ele)}});
      if (!error.empty()) return Error{error};
      return Ok{};
    }
    case MeshFormat::kGmsh:
      return writeTextFile(path, formatGmsh41(mesh));
    case MeshFormat::kVtk:
      return writeTextFile(path, formatVtk(mesh, mesh.restPositions(), fields));
  }
  return Error{path.string() + ": unsupported format"};
}

}  // namespace torsion
