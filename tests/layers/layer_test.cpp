// The layers of SAGE Fleet, as the build means them: each folder is a library that may include
// only the layers below it, and the heavy or transport-specific headers stay where they belong
// (Cyclone DDS in the transports and the app, CLI11 in one file of the app, file writing in the
// run-directory code). The build links them that way; this test reads every source file and
// fails on an include that crosses a layer, so a new one cannot slip in through a shared
// include path. Its own checker is tested on a made-up tree with a forbidden include.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace sage {
namespace {

namespace fs = std::filesystem;

struct SourceFile {
  std::string path;  // relative to the repository, e.g. "server/node/server_node.cpp"
  std::string text;
};

// The layer a file belongs to: the longest matching folder.
std::string LayerOf(const std::string& path) {
  static const std::vector<std::pair<std::string, std::string>> kFolders = {
      {"maps/scenario/", "scenario"}, {"maps/", "maps"},           {"agents/node/", "agents_node"},
      {"agents/", "agents"},          {"proto/security/", "security"}, {"proto/", "proto"},         {"server/report/", "report"}, {"server/live/", "live"},
      {"server/node/", "server_node"}, {"server/app/", "app"},     {"server/", "server"},
  };
  for (const auto& [folder, layer] : kFolders)
    if (path.rfind(folder, 0) == 0) return layer;
  return "";
}

// Which layers each layer may include (itself included).
const std::map<std::string, std::set<std::string>>& AllowedLayers() {
  static const std::map<std::string, std::set<std::string>> kAllowed = {
      {"scenario", {"scenario"}},
      {"maps", {"scenario", "maps"}},
      {"agents", {"scenario", "maps", "agents"}},
      {"proto", {"proto"}},
      {"security", {"proto", "security"}},
      {"agents_node", {"scenario", "maps", "agents", "agents_node", "proto"}},
      {"server", {"scenario", "maps", "agents", "server"}},
      {"report", {"scenario", "maps", "agents", "server", "report"}},
      {"live", {"scenario", "maps", "agents", "server", "report", "live"}},
      {"server_node", {"scenario", "maps", "agents", "agents_node", "proto", "server", "report", "live", "server_node"}},
      {"app", {"scenario", "maps", "agents", "agents_node", "proto", "security", "server", "report", "live", "server_node",
               "app"}},
  };
  return kAllowed;
}

// Headers of outside libraries that only some layers may use.
const std::map<std::string, std::set<std::string>>& ExternalRules() {
  static const std::map<std::string, std::set<std::string>> kRules = {
      {"dds/", {"proto", "agents_node", "server_node", "app"}},  // Cyclone DDS: the transports
      {"CLI/", {"app"}},                                        // CLI11: the command line
      {"nlohmann/", {"report", "live"}},                        // JSON/CBOR: the run files, Foxglove's requests
      {"httplib.h", {"live"}},                                  // the live view's web server
      {"websocketpp/", {"live"}},                               // ... and its Foxglove WebSocket
      {"asio", {"live"}},
      {"octomap/", {"maps"}},
      {"gdal", {"maps"}},                                       // GDAL: the seabed map files
      {"cpl_", {"maps"}},
      {"ogr_", {"maps"}},
      {"box2d/", {"agents"}},
      {"yaml-cpp/", {"scenario"}},
      {"openssl/", {"security"}},                               // OpenSSL: the security files
      {"cairo", {"report"}},                                    // cairo, librsvg: the plots' PNGs
      {"librsvg/", {"report"}},
      {"glib", {"report"}},
  };
  return kRules;
}

// Every broken rule, one line each: "server/mission.cpp: includes proto/qos.h (layer proto)".
std::vector<std::string> Violations(const std::vector<SourceFile>& files) {
  std::vector<std::string> out;
  const std::regex include(R"(^\s*#\s*include\s*([<"])([^>"]+)[>"])");
  const std::regex writes_file(R"(std::ofstream|\bofstream\b|fopen\s*\([^;]*"[wa]|\bfwrite\s*\()");
  std::map<std::string, int> cli_files;
  for (const SourceFile& f : files) {
    const std::string layer = LayerOf(f.path);
    if (layer.empty()) continue;
    std::istringstream lines(f.text);
    std::string line;
    int number = 0;
    while (std::getline(lines, line)) {
      ++number;
      std::smatch m;
      const std::string where = f.path + ":" + std::to_string(number) + ": ";
      if (std::regex_search(line, m, writes_file) && layer != "report") {
        out.push_back(where + "writes a file outside the run-directory code (server/report/)");
      }
      if (!std::regex_search(line, m, include)) continue;
      const std::string header = m[2];
      // OctoMap's templates cost seconds in every file that sees them: headers forward declare
      // its types, and only the risk tree's own header (included by its few users) spells them out.
      const bool is_header = f.path.size() > 2 && f.path.compare(f.path.size() - 2, 2, ".h") == 0;
      if (is_header && f.path != "maps/risk_octree.h" &&
          (header.rfind("octomap/", 0) == 0 || header == "maps/risk_octree.h")) {
        out.push_back(where + "includes " + header + " in a header (forward declare OctoMap's types)");
      }
      if (m[1] == "\"") {
        const std::string target = LayerOf(header);
        if (target.empty()) {
          if (layer != "proto") out.push_back(where + "includes \"" + header + "\", which is no layer's header");
        } else if (!AllowedLayers().at(layer).count(target)) {
          out.push_back(where + "includes " + header + " (layer " + target + ") from layer " + layer);
        }
        continue;
      }
      for (const auto& [prefix, layers] : ExternalRules()) {
        if (header.rfind(prefix, 0) != 0) continue;
        if (!layers.count(layer)) out.push_back(where + "includes <" + header + "> in layer " + layer);
        if (prefix == "CLI/") ++cli_files[f.path];
      }
    }
  }
  // CLI11 costs seconds of compile time in every file that includes it: one file only.
  if (cli_files.size() > 1) {
    std::string names;
    for (const auto& [path, count] : cli_files) names += " " + path;
    out.push_back("CLI11 is included by " + std::to_string(cli_files.size()) + " files (one allowed):" + names);
  }
  return out;
}

std::vector<SourceFile> ProjectSources() {
  std::vector<SourceFile> files;
  const fs::path root(SAGE_SOURCE_DIR);
  for (const char* top : {"maps", "agents", "proto", "server"}) {
    for (const fs::directory_entry& e : fs::recursive_directory_iterator(root / top)) {
      const std::string ext = e.path().extension().string();
      if (!e.is_regular_file() || (ext != ".h" && ext != ".cpp" && ext != ".idl")) continue;
      std::ifstream in(e.path());
      std::stringstream text;
      text << in.rdbuf();
      files.push_back({fs::relative(e.path(), root).generic_string(), text.str()});
    }
  }
  return files;
}

// The real tree keeps its layers (the list of sources is not empty: the test reads them).
TEST(Layers, NoIncludeCrossesALayer) {
  const std::vector<SourceFile> files = ProjectSources();
  ASSERT_GT(files.size(), 50u);
  const std::vector<std::string> violations = Violations(files);
  for (const std::string& v : violations) ADD_FAILURE() << v;
}

// The checker finds each kind of crossing in a made-up tree, and accepts the same tree without
// them: a core file reaching into the transport, DDS in an algorithm, CLI11 in a second file,
// a file written outside the report code, JSON in the core, OctoMap in a header.
TEST(Layers, CheckerCatchesForbiddenIncludes) {
  const std::vector<SourceFile> clean = {
      {"server/mission.cpp", "#include \"server/mission.h\"\n#include \"agents/agent_host.h\"\n"},
      {"server/app/cli.cpp", "#include <CLI/CLI.hpp>\n#include \"proto/qos.h\"\n"},
      {"server/report/run_directory.cpp", "std::ofstream out(path);\n#include <nlohmann/json.hpp>\n"},
      {"maps/seabed_map.cpp", "#include <octomap/OcTree.h>\n"},
      {"maps/risk_octree.h", "#include <octomap/OcTreeNode.h>\n"},
      {"maps/risk_layer.cpp", "#include \"maps/risk_octree.h\"\n"},
  };
  EXPECT_TRUE(Violations(clean).empty());
  const std::vector<std::pair<SourceFile, std::string>> bad = {
      {{"server/mission.cpp", "#include \"proto/qos.h\"\n"}, "includes proto/qos.h (layer proto) from layer server"},
      {{"agents/ergodic_controller.cpp", "#include <dds/dds.h>\n"}, "includes <dds/dds.h> in layer agents"},
      {{"server/app/launch.cpp", "#include <CLI/CLI.hpp>\n"}, "CLI11 is included by 2 files"},
      {{"server/mission_core.cpp", "  std::ofstream out(\"x\");\n"}, "writes a file outside the run-directory code"},
      {{"server/metrics.cpp", "#include <nlohmann/json.hpp>\n"}, "includes <nlohmann/json.hpp> in layer server"},
      {{"maps/world.cpp", "#include \"server/mission_core.h\"\n"}, "(layer server) from layer maps"},
      {{"maps/world.h", "#include <octomap/OcTree.h>\n"}, "includes octomap/OcTree.h in a header"},
      {{"maps/world.h", "#include \"maps/risk_octree.h\"\n"}, "includes maps/risk_octree.h in a header"},
      {{"server/fleet_server.cpp", "#include <librsvg/rsvg.h>\n"}, "includes <librsvg/rsvg.h> in layer server"},
  };
  for (const auto& [file, expected] : bad) {
    std::vector<SourceFile> tree = clean;
    tree.push_back(file);
    const std::vector<std::string> found = Violations(tree);
    ASSERT_EQ(found.size(), 1u) << file.path << ": " << expected;
    EXPECT_NE(found[0].find(expected), std::string::npos) << found[0];
  }
}

}  // namespace
}  // namespace sage
