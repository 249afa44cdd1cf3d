#pragma once
// The live view's page, script and style, compiled into the binary from server/live/web/ (the
// build turns each file into bytes of a generated source, embed_web_assets.cmake), so the page
// needs nothing from the network and nothing from the disk at run time.
#include <span>
#include <string_view>

namespace sage::live {

struct WebAsset {
  std::string_view path;          ///< as requested, e.g. "/app.js" ("/" for the page)
  std::string_view content_type;
  std::string_view body;
};

std::span<const WebAsset> WebAssets();

}  // namespace sage::live
