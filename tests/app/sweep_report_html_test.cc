// The sweep's report page: the C++ that writes it (base64, thumbnails, the embedded data), and
// the page itself drawn by a real browser, headless Chromium, whose DOM after the scripts ran
// must show every scene, every figure's plot and the thumbnails, and no script error.

#include "app/sweep/report_html.h"

#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <string>
#include <vector>

namespace hgrasp::app::sweep {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// The figures the page plots (its FIGURES), one histogram each when any scene has values.
const std::vector<std::string> kFigures = {
    "center_mm", "max_edge_mm", "yaw_deg", "range_rms_mm", "coverage", "outlier_fraction",
    "contact_mm", "servo_mm", "servo_deg", "true_rise_mm", "wall_s"};

// A fresh folder under the system's temp folder, removed with everything in it at the end.
class TempDir {
 public:
  TempDir() {
    std::string pattern = (fs::temp_directory_path() / "hgrasp_report_XXXXXX").string();
    if (mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

int Count(const std::string& text, const std::string& what) {
  int n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void WriteFile(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

// A 320 x 240 picture like the pipeline's: a gradient with a box outline, written as PNG.
void WritePicture(const fs::path& path, int shade) {
  cv::Mat image(240, 320, CV_8UC3);
  for (int r = 0; r < image.rows; ++r) {
    for (int c = 0; c < image.cols; ++c) image.at<cv::Vec3b>(r, c) = cv::Vec3b(shade, r, c * 255 / 320);
  }
  cv::rectangle(image, {100, 80}, {220, 170}, {0, 255, 255}, 3);
  fs::create_directories(path.parent_path());
  ASSERT_TRUE(cv::imwrite(path.string(), image)) << path;
}

json OkScene(const std::string& name, double score, double centre_mm) {
  const std::string dir = "scenes/" + name;
  return {
      {"scene", name}, {"file", "scenarios/" + name + ".yaml"}, {"dir", dir}, {"seed", 1},
      {"stage", "run"}, {"status", "ok"}, {"ok", true}, {"failure", nullptr},
      {"failure_detail", nullptr}, {"exit_code", 0}, {"signal", nullptr}, {"wall_s", 6.3},
      {"robot_s", 20.4},
      {"range", {{"points", 62460}, {"rms_mm", 0.41}, {"outliers", 12},
                 {"outlier_fraction", 0.0002}, {"coverage", 0.987}}},
      {"hoover", {{"truth_regions", 5}, {"correct", 5}, {"over", 0}, {"under", 0},
                  {"missed", 0}, {"noise", 0}}},
      {"boxes", {{{"object", "yellow_box"}, {"found", true}, {"box", 0}, {"center_mm", centre_mm},
                  {"edge_mm", {0.2, 1.9, 0.3}}, {"max_edge_mm", 1.9}, {"yaw_deg", -0.17},
                  {"color_name", "yellow"}, {"true_color_name", "yellow"}, {"color_ok", true},
                  {"within_tolerance", true}},
                 {{"object", "red_box"}, {"found", true}, {"box", 1}, {"center_mm", 0.9},
                  {"edge_mm", {1.2, 0.4, 0.3}}, {"max_edge_mm", 1.2}, {"yaw_deg", 0.8},
                  {"color_name", "red"}, {"true_color_name", "red"}, {"color_ok", true},
                  {"within_tolerance", true}}}},
      {"boxes_found", 2}, {"boxes_total", 2}, {"target_object", "yellow_box"},
      {"grasp", {{"planned", true}, {"arm", "right"}, {"contact_mm", {0.7, 0.9}}}},
      {"servo", {{"gripper_to_plan_mm", 1.3}, {"gripper_to_plan_deg", 0.35}}},
      {"lift", {{"lifted", true}, {"true_rise_mm", 49.2}}},
      {"pictures", {{"segments", dir + "/segments.png"}, {"grasp", dir + "/grasp.png"},
                    {"servo", {dir + "/servo_servo_start.png", dir + "/servo_grasp_reached.png"}}}},
      {"score", score}};
}

// A scene that got nowhere: every figure null, no boxes, no pictures.
json FailedScene(const std::string& name, const std::string& status, const json& failure,
                 const json& detail, double score) {
  return {{"scene", name}, {"file", "scenarios/" + name + ".yaml"}, {"dir", "scenes/" + name},
          {"seed", 3}, {"stage", "run"}, {"status", status}, {"ok", false},
          {"failure", failure}, {"failure_detail", detail}, {"exit_code", nullptr},
          {"signal", nullptr}, {"wall_s", nullptr}, {"robot_s", nullptr}, {"range", nullptr},
          {"hoover", nullptr}, {"boxes", json::array()}, {"boxes_found", nullptr},
          {"boxes_total", nullptr}, {"target_object", nullptr}, {"grasp", nullptr},
          {"servo", nullptr}, {"lift", nullptr}, {"pictures", nullptr}, {"score", score}};
}

// 7 scenes: 3 ok, one failed (no_target) named to break a careless page, a crash, a timeout and
// a bad input. Scene 1 has three real pictures of its four (one servo picture is missing), scene
// 2 one (its grasp picture is missing): 4 thumbnails in all.
json SyntheticSummary(const fs::path& sweep_dir) {
  json scenes = json::array();
  scenes.push_back(OkScene("random_boxes_1", 0.12, 0.2));
  scenes.push_back(OkScene("random_boxes_2", 0.30, 2.5));
  scenes[1]["pictures"].erase("servo");
  json evil = OkScene("evil</script><b>bold</b>", 2.0, 0.4);
  evil["status"] = "failed";
  evil["ok"] = false;
  evil["failure"] = "no_target";
  evil["failure_detail"] = "no box of colour \"blue\" </script><!-- among 2";
  evil["grasp"] = nullptr;
  evil["servo"] = nullptr;
  evil["lift"] = nullptr;
  evil["pictures"] = {{"segments", nullptr}};
  scenes.push_back(evil);
  json crash = FailedScene("crash_scene", "crash", "crash", "killed by signal 11 (SIGSEGV)", 10.0);
  crash["signal"] = 11;
  crash.erase("pictures");
  scenes.push_back(crash);
  json timeout = OkScene("slow_scene", 5.0, 7.5);
  timeout["status"] = "timeout";
  timeout["ok"] = false;
  timeout["failure"] = "timeout";
  timeout["failure_detail"] = "past the time limit of 120 s";
  timeout["boxes"][1] = {{"object", "red_box"}, {"found", false}, {"box", nullptr},
                         {"center_mm", nullptr}, {"edge_mm", nullptr}, {"max_edge_mm", nullptr},
                         {"yaw_deg", nullptr}, {"color_name", nullptr},
                         {"true_color_name", "red"}, {"color_ok", nullptr},
                         {"within_tolerance", false}};
  timeout["boxes_found"] = 1;
  timeout["servo"] = nullptr;
  timeout["lift"] = nullptr;
  timeout["pictures"] = json::object();
  scenes.push_back(timeout);
  json bad = FailedScene("bad_scene", "bad_input", "bad_input",
                         "scenario: boxes[0].size: expected 3 numbers, got 2", 0.0);
  bad["exit_code"] = 2;
  bad["score"] = nullptr;  // sorts last
  scenes.push_back(bad);
  json scan_only = OkScene("random_boxes_7", 0.05, 0.1);
  scan_only["stage"] = "scan";
  scan_only["grasp"] = nullptr;
  scan_only["servo"] = nullptr;
  scan_only["lift"] = nullptr;
  scan_only["pictures"] = nullptr;
  scenes.push_back(scan_only);

  const fs::path one = sweep_dir / "scenes/random_boxes_1";
  WritePicture(one / "segments.png", 40);
  WritePicture(one / "grasp.png", 120);
  WritePicture(one / "servo_servo_start.png", 200);
  WritePicture(sweep_dir / "scenes/random_boxes_2/segments.png", 80);

  return {{"sweep", {{"stage", "run"}, {"jobs", 2}, {"time_limit_s", 120},
                     {"started_utc", "2026-12-01T21:00:00Z"}, {"scenes", 7}}},
          {"totals", {{"scenes", 7}, {"ok", 3}, {"failed", 4},
                      {"failures", {{"no_target", 1}, {"crash", 1}, {"timeout", 1}, {"bad_input", 1}}},
                      {"boxes", 12}, {"boxes_found", 10}, {"boxes_within_tolerance", 9},
                      {"lifted", 3}, {"wall_s", 70.2}, {"sweep_wall_s", 40.1},
                      {"scenes_per_hour", 628.3}}},
          {"scenes", scenes}};
}

json EmptySummary() {
  return {{"sweep", {{"stage", "scan"}, {"jobs", 1}, {"time_limit_s", 120},
                     {"started_utc", "2026-12-01T21:00:00Z"}, {"scenes", 0}}},
          {"totals", {{"scenes", 0}, {"ok", 0}, {"failed", 0}, {"failures", json::object()},
                      {"boxes", 0}, {"boxes_found", 0}, {"boxes_within_tolerance", 0},
                      {"lifted", 0}, {"wall_s", 0}, {"sweep_wall_s", 0},
                      {"scenes_per_hour", nullptr}}},
          {"scenes", json::array()}};
}

// The JSON text inside <script type="application/json" id="data">.
std::string DataBlob(const std::string& html) {
  const std::string open = "<script type=\"application/json\" id=\"data\">";
  const size_t begin = html.find(open);
  if (begin == std::string::npos) return {};
  const size_t end = html.find("</script>", begin);
  return html.substr(begin + open.size(), end - begin - open.size());
}

// Runs `command` through the shell; its stdout, and its exit status in *status.
std::string Shell(const std::string& command, int* status) {
  std::string out;
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) {
    *status = -1;
    return out;
  }
  std::array<char, 65536> buf;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) out.append(buf.data(), n);
  const int raw = pclose(pipe);
  *status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  return out;
}

// Headless Chromium as root in a container: no sandbox (it refuses to run as root with one), no
// GPU, no /dev/shm (a container's is 64 MB), a profile of its own. The virtual time budget lets
// the page's scripts finish before the DOM is dumped; `timeout` stops a hung browser.
std::string ChromiumCommand(const fs::path& profile, const std::string& action,
                            const fs::path& page, const fs::path& log) {
  return "timeout 60 chromium --headless=new --no-sandbox --disable-gpu --disable-dev-shm-usage"
         " --no-first-run --no-default-browser-check --user-data-dir='" + profile.string() +
         "' --virtual-time-budget=5000 " + action + " 'file://" + page.string() + "' 2>'" +
         log.string() + "'";
}

// `html` without the contents of its <script> elements, whose source would count as markup.
std::string WithoutScripts(const std::string& html) {
  std::string out;
  size_t at = 0;
  for (size_t open; (open = html.find("<script", at)) != std::string::npos;) {
    const size_t body = html.find('>', open);
    const size_t close = html.find("</script>", body);
    if (body == std::string::npos || close == std::string::npos) break;
    out.append(html, at, body + 1 - at);
    at = close;
  }
  out.append(html, at, std::string::npos);
  return out;
}

// The page's DOM after its scripts ran, as Chromium dumps it, without the scripts' source.
// Chromium is a dependency of the tests: without it this fails, naming the package.
void RenderedDom(const fs::path& page, const fs::path& work, std::string* dom) {
  int status = 0;
  Shell("command -v chromium >/dev/null 2>&1", &status);
  ASSERT_EQ(status, 0) << "chromium is not installed: the report page test needs Debian's "
                          "package `chromium` (apt-get install chromium)";
  const fs::path log = work / "chromium.log";
  *dom = Shell(ChromiumCommand(work / "profile", "--dump-dom", page, log), &status);
  ASSERT_EQ(status, 0) << "chromium failed (status " << status << "; 124: over 60 s):\n"
                       << ReadFile(log);
  ASSERT_NE(dom->find("</html>"), std::string::npos) << "no DOM dumped:\n" << ReadFile(log);
  *dom = WithoutScripts(*dom);
}

// The value of the attribute `name` (its first occurrence), or "(none)".
std::string Attribute(const std::string& dom, const std::string& name) {
  const std::string key = name + "=\"";
  const size_t at = dom.find(key);
  if (at == std::string::npos) return "(none)";
  return dom.substr(at + key.size(), dom.find('"', at + key.size()) - at - key.size());
}

// The text in <pre id="errors">, or "(no #errors)".
std::string ErrorsText(const std::string& dom) {
  const size_t at = dom.find("id=\"errors\"");
  if (at == std::string::npos) return "(no #errors)";
  const size_t begin = dom.find('>', at) + 1;
  return dom.substr(begin, dom.find("</pre>", begin) - begin);
}

TEST(Base64, MatchesRfc4648Vectors) {
  EXPECT_EQ(Base64(""), "");
  EXPECT_EQ(Base64("f"), "Zg==");
  EXPECT_EQ(Base64("fo"), "Zm8=");
  EXPECT_EQ(Base64("foo"), "Zm9v");
  EXPECT_EQ(Base64("foob"), "Zm9vYg==");
  EXPECT_EQ(Base64("fooba"), "Zm9vYmE=");
  EXPECT_EQ(Base64("foobar"), "Zm9vYmFy");
  EXPECT_EQ(Base64(std::string("\xff\xfe\x00", 3)), "//4A");
}

TEST(JpegThumbnail, Is160WideWithTheAspectKept) {
  TempDir tmp;
  WritePicture(tmp.path() / "p.png", 0);
  const std::string jpeg = JpegThumbnail(tmp.path() / "p.png");
  ASSERT_FALSE(jpeg.empty());
  EXPECT_EQ(static_cast<unsigned char>(jpeg[0]), 0xFF);  // JPEG SOI marker
  EXPECT_EQ(static_cast<unsigned char>(jpeg[1]), 0xD8);
  const cv::Mat back = cv::imdecode(std::vector<uchar>(jpeg.begin(), jpeg.end()), cv::IMREAD_COLOR);
  EXPECT_EQ(back.cols, 160);
  EXPECT_EQ(back.rows, 120);
  EXPECT_LT(jpeg.size(), 12000u) << "thumbnails must stay small";
}

TEST(JpegThumbnail, IsEmptyForAMissingOrBrokenFile) {
  TempDir tmp;
  EXPECT_TRUE(JpegThumbnail(tmp.path() / "missing.png").empty());
  WriteFile(tmp.path() / "broken.png", "not a picture");
  EXPECT_TRUE(JpegThumbnail(tmp.path() / "broken.png").empty());
  EXPECT_TRUE(JpegThumbnail(tmp.path()).empty());  // a folder
}

TEST(ReportHtml, EmbedsTheSummaryUnchangedAndCannotBeBrokenOutOf) {
  TempDir tmp;
  const json summary = SyntheticSummary(tmp.path());
  const std::string html = ReportHtml(summary, tmp.path());
  const std::string blob = DataBlob(html);
  ASSERT_FALSE(blob.empty());
  EXPECT_EQ(blob.find('<'), std::string::npos) << "no '<' may reach the data element";
  const json data = json::parse(blob);
  EXPECT_EQ(data["summary"], summary);
  ASSERT_EQ(data["thumbs"].size(), 7u);  // one list per scene
  ASSERT_EQ(data["thumbs"][0].size(), 3u);
  EXPECT_EQ(data["thumbs"][0][0]["name"], "segments");
  EXPECT_EQ(data["thumbs"][0][0]["href"], "scenes/random_boxes_1/segments.png");
  EXPECT_EQ(data["thumbs"][0][1]["name"], "grasp");
  EXPECT_EQ(data["thumbs"][0][2]["name"], "servo_servo_start");
  EXPECT_EQ(data["thumbs"][1].size(), 1u);
  for (size_t i = 2; i < 7; ++i) EXPECT_TRUE(data["thumbs"][i].empty()) << i;
  // Self-contained: no URL of any scheme, no external script or style.
  EXPECT_EQ(html.find("://"), std::string::npos);
  EXPECT_EQ(html.find("<script src"), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);
}

TEST(ReportHtml, WithInvalidUtf8InANameStillWrites) {
  json summary = EmptySummary();
  summary["scenes"].push_back({{"scene", std::string("bad\xff name")}});
  const std::string html = ReportHtml(summary, fs::temp_directory_path());
  EXPECT_NO_THROW(json::parse(DataBlob(html)));
}

TEST(ReportPage, DrawsEveryScenePlotAndThumbnailInChromium) {
  TempDir tmp;
  const json summary = SyntheticSummary(tmp.path());
  const fs::path page = tmp.path() / "report.html";
  WriteFile(page, ReportHtml(summary, tmp.path()));
  std::string dom;
  ASSERT_NO_FATAL_FAILURE(RenderedDom(page, tmp.path(), &dom));

  EXPECT_EQ(ErrorsText(dom), "");
  EXPECT_EQ(Attribute(dom, "data-rendered"), "1");
  EXPECT_EQ(Attribute(dom, "data-rows"), "7");
  EXPECT_EQ(Count(dom, "<tr class=\"scene "), 7);
  for (const std::string& id : kFigures) {
    EXPECT_NE(dom.find("data-figure=\"" + id + "\""), std::string::npos) << id;
  }
  EXPECT_GE(Count(dom, "<svg"), static_cast<int>(kFigures.size()));
  EXPECT_EQ(Count(dom, "no values"), 0);
  EXPECT_EQ(Count(dom, "src=\"data:image/jpeg;base64,"), 4);
  EXPECT_NE(dom.find("href=\"scenes/random_boxes_1/grasp.png\""), std::string::npos);
  // Worst first: the crash (score 10) heads the table, the bad input (score null) ends it.
  EXPECT_EQ(Attribute(dom, "data-i"), "3");
  EXPECT_LT(dom.find("data-i=\"0\""), dom.find("data-i=\"5\""));
  // Each kind of failure marked; nulls shown as a dash.
  for (const char* status : {"st-failed bad", "st-crash bad", "st-timeout bad", "st-bad_input bad"}) {
    EXPECT_NE(dom.find(status), std::string::npos) << status;
  }
  EXPECT_NE(dom.find("<td>\xE2\x80\x93</td>"), std::string::npos);
  // The scene name is text on the page, not markup.
  EXPECT_NE(dom.find("evil&lt;/script&gt;&lt;b&gt;bold&lt;/b&gt;"), std::string::npos);
  EXPECT_EQ(dom.find("<b>"), std::string::npos);
}

TEST(ReportPage, DrawsAnEmptySweep) {
  TempDir tmp;
  const fs::path page = tmp.path() / "report.html";
  WriteFile(page, ReportHtml(EmptySummary(), tmp.path()));
  std::string dom;
  ASSERT_NO_FATAL_FAILURE(RenderedDom(page, tmp.path(), &dom));
  EXPECT_EQ(ErrorsText(dom), "");
  EXPECT_EQ(Attribute(dom, "data-rendered"), "1");
  EXPECT_EQ(Attribute(dom, "data-rows"), "0");
  EXPECT_EQ(Count(dom, "<svg"), 0);
  EXPECT_EQ(Count(dom, "no values"), static_cast<int>(kFigures.size()));
}

TEST(ReportPage, DrawsASummaryWithNothingInIt) {
  TempDir tmp;
  const fs::path page = tmp.path() / "report.html";
  WriteFile(page, ReportHtml(json::object(), tmp.path()));
  std::string dom;
  ASSERT_NO_FATAL_FAILURE(RenderedDom(page, tmp.path(), &dom));
  EXPECT_EQ(ErrorsText(dom), "");
  EXPECT_EQ(Attribute(dom, "data-rendered"), "1");
  EXPECT_EQ(Attribute(dom, "data-rows"), "0");
}

}  // namespace
}  // namespace hgrasp::app::sweep
