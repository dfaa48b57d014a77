#include "slam_mms_run/json_file.hpp"

#include <fstream>
#include <sstream>

namespace slam_mms::app {
namespace fs = std::filesystem;
using Json = nlohmann::json;

StatusOr<Json> ReadJsonFile(const fs::path& file) {
  std::ifstream in(file);
  if (!in) return NotFoundError("cannot open " + file.string());
  std::stringstream text;
  text << in.rdbuf();
  Json j = Json::parse(text.str(), nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) return DataLossError(file.string() + ": not valid JSON");
  return j;
}

Status WriteJsonFile(const Json& j, const fs::path& file, int indent) {
  const fs::path tmp = file.string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    out << j.dump(indent) << '\n';
    out.flush();
    if (!out) return UnavailableError("cannot write " + tmp.string());
  }
  std::error_code ec;
  fs::rename(tmp, file, ec);
  if (ec) return UnavailableError("cannot rename " + tmp.string() + ": " + ec.message());
  return OkStatus();
}

}  // namespace slam_mms::app
