// Output folders: new folders appear whole, earlier outputs are replaced file by file under a
// journal, a commit cut off between its renames is finished by the next run, and nothing a user
// made is ever touched.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/errors.h"
#include "error_of.h"
#include "io/files.h"
#include "io/output_folder.h"

namespace iphong::io {
namespace {
namespace fs = std::filesystem;

class OutputFolderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("iphong-out-" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  static std::string Read(const std::string& path) { return ReadTextFile(path); }
  static void Write(const std::string& path, const std::string& text) {
    std::ofstream(path, std::ios::binary) << text;
  }
  // Names in a folder, hidden ones included.
  static std::set<std::string> Names(const std::string& folder) {
    std::set<std::string> names;
    for (const auto& e : fs::directory_iterator(folder)) names.insert(e.path().filename());
    return names;
  }
  static OutputFolderOptions Command(const std::string& command, bool overwrite = false) {
    OutputFolderOptions o;
    o.command = command;
    o.overwrite = overwrite;
    return o;
  }
  void Produce(const std::string& target, const std::string& command,
               const std::map<std::string, std::string>& files, bool overwrite = false) {
    OutputFolder out(target, Command(command, overwrite));
    for (const auto& [name, text] : files) WriteTextFile(out.file(name), text);
    out.Commit();
  }
  fs::path dir_;
};

using test::ErrorOf;

TEST_F(OutputFolderTest, NewFolderAppearsWholeWithItsManifest) {
  Produce(Path("a/b/out"), "render", {{"x.txt", "1"}, {"sub/y.txt", "22"}});
  EXPECT_EQ(Read(Path("a/b/out/x.txt")), "1");
  EXPECT_EQ(Read(Path("a/b/out/sub/y.txt")), "22");
  const auto manifest =
      nlohmann::json::parse(Read(Path("a/b/out/.iphong-manifest.json")))["commands"]["render"];
  EXPECT_EQ(manifest["x.txt"]["size"], 1);
  EXPECT_EQ(manifest["sub/y.txt"]["size"], 2);
  EXPECT_EQ(Names(Path("a/b")), (std::set<std::string>{"out"}));  // no staging left beside it
}

TEST_F(OutputFolderTest, AbandonedOutputLeavesNothingNotEvenTheParentsItMade) {
  {
    OutputFolder out(Path("a/b/out"), Command("render"));
    WriteTextFile(out.file("x.txt"), "1");
  }
  EXPECT_TRUE(fs::is_empty(dir_));
  fs::create_directories(Path("empty"));
  {
    OutputFolder out(Path("empty"), Command("render"));
    WriteTextFile(out.file("x.txt"), "1");
    AbandonOutputFolders();  // as SIGINT does
    EXPECT_NE(ErrorOf([&] { out.Commit(); }).find("interrupted"), std::string::npos);
  }
  EXPECT_EQ(Names(dir_.string()), (std::set<std::string>{"empty"}));
  EXPECT_TRUE(fs::is_empty(Path("empty")));
}

// A signal after an output was committed and its folder object released (the process is still
// finishing) finds it complete: the interrupt's message said "nothing was written" beside a
// folder holding the new output (an --overwrite render under SIGHUP, 1 of 24 in the CLI test).
TEST_F(OutputFolderTest, AnOutputCommittedAndReleasedIsReportedComplete) {
  Produce(Path("done"), "render", {{"x.txt", "1"}});
  WriteSingleOutputFile("eval", Path("single.png"), false, {},
                        [](const std::string& temp) { WriteTextFile(temp, "2"); });
  const AbandonReport report = AbandonOutputFolders();
  EXPECT_EQ(report.removed, 0u);
  const auto listed = [&](const std::string& target) {
    return std::count(report.complete.begin(), report.complete.end(), target) > 0;
  };
  EXPECT_TRUE(listed(Path("done")));
  EXPECT_TRUE(listed(Path("single.png")));
  // A long session (Python writing output after output) keeps only the latest few.
  for (int i = 0; i < 40; ++i) {
    WriteSingleOutputFile("eval", Path("many" + std::to_string(i) + ".png"), false, {},
                          [](const std::string& temp) { WriteTextFile(temp, "3"); });
  }
  const AbandonReport later = AbandonOutputFolders();
  EXPECT_LE(later.complete.size(), 16u);
  EXPECT_EQ(later.complete.back(), Path("many39.png"));
}

TEST_F(OutputFolderTest, EmptyFolderIsUsedAndKeepsItsPermissions) {
  fs::create_directories(Path("out"));
  fs::permissions(Path("out"),
                  fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec);
  Produce(Path("out"), "normals", {{"n.txt", "n"}});
  EXPECT_EQ(Read(Path("out/n.txt")), "n");
  EXPECT_EQ(fs::status(Path("out")).permissions() & fs::perms::all,
            fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec);
}

TEST_F(OutputFolderTest, RefusesWhatItMayNotTouch) {
  Write(Path("file"), "mine");
  EXPECT_EQ(ErrorOf([&] { OutputFolder(Path("file"), Command("normals")); }),
            Path("file") + ": exists and is not a folder; choose a folder for the output");
  fs::create_directories(Path("user"));
  Write(Path("user/photo.png"), "precious");
  EXPECT_NE(ErrorOf([&] {
              OutputFolder(Path("user"), Command("normals"));
            }).find("is not empty and was not written by iphong"),
            std::string::npos);
  Produce(Path("out"), "normals", {{"n.txt", "n"}});
  EXPECT_NE(ErrorOf([&] { OutputFolder(Path("out"), Command("normals")); }).find("--overwrite"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] {
              OutputFolder(Path("out"), Command("render", true));
            }).find("holds the output of `iphong normals`"),
            std::string::npos);
  OutputFolderOptions o = Command("normals");
  o.inputs = {Path("user")};
  EXPECT_NE(ErrorOf([&] { OutputFolder(Path("user/sub"), o); }).find("lies inside the input"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { OutputFolder(dir_.string(), o); }).find("contains the input"),
            std::string::npos);
  EXPECT_EQ(Read(Path("file")), "mine");
  EXPECT_EQ(Names(Path("user")), (std::set<std::string>{"photo.png"}));
  EXPECT_THROW(OutputFolder(Path("x"), Command("a")).file(".iphong-manifest.json"),
               std::logic_error);
  EXPECT_THROW(OutputFolder(Path("y"), Command("a")).file("../escape.txt"), std::logic_error);
}

TEST_F(OutputFolderTest, OverwriteReplacesOnlyIphongsUnchangedFiles) {
  Produce(Path("out"), "normals", {{"a.txt", "old a"}, {"b.txt", "old b"}, {"c/d.txt", "d"}});
  Write(Path("out/notes.txt"), "user notes");
  Produce(Path("out"), "normals", {{"a.txt", "new a"}}, /*overwrite=*/true);
  EXPECT_EQ(Read(Path("out/a.txt")), "new a");
  EXPECT_FALSE(fs::exists(Path("out/b.txt")));  // the earlier run's, not produced again
  EXPECT_FALSE(fs::exists(Path("out/c")));      // its folder went with its only file
  EXPECT_EQ(Read(Path("out/notes.txt")), "user notes");
  EXPECT_EQ(Names(Path("out")),
            (std::set<std::string>{"a.txt", "notes.txt", ".iphong-manifest.json"}));

  // A file the user edited is theirs now: not replaced (error), and not removed as stale.
  Produce(Path("out2"), "normals", {{"a.txt", "a"}, {"b.txt", "b"}});
  Write(Path("out2/a.txt"), "edited a");
  EXPECT_NE(ErrorOf([&] {
              Produce(Path("out2"), "normals", {{"a.txt", "x"}}, true);
            }).find("a.txt: changed since `iphong normals` wrote it"),
            std::string::npos);
  Write(Path("out2/b.txt"), "edited b");
  Write(Path("out2/a.txt"), "a");  // the same size as iphong's, but written later: still changed
  fs::last_write_time(Path("out2/a.txt"),
                      fs::last_write_time(Path("out2/a.txt")) + std::chrono::seconds(1));
  EXPECT_NE(ErrorOf([&] {
              Produce(Path("out2"), "normals", {{"a.txt", "x"}}, true);
            }).find("changed since"),
            std::string::npos);
  EXPECT_EQ(Read(Path("out2/b.txt")), "edited b");

  // A user's file where iphong wants to write is never replaced.
  Produce(Path("out3"), "normals", {{"a.txt", "a"}});
  Write(Path("out3/mesh.ply"), "my mesh");
  OutputFolderOptions join = Command("integrate");
  join.joins = {"normals"};
  EXPECT_NE(ErrorOf([&] {
              OutputFolder out(Path("out3"), join);
              WriteTextFile(out.file("mesh.ply"), "iphong's mesh");
              out.Commit();
            }).find("mesh.ply: exists and was not written by iphong"),
            std::string::npos);
  EXPECT_EQ(Read(Path("out3/mesh.ply")), "my mesh");
}

TEST_F(OutputFolderTest, JoinedCommandsAddTheirFilesAndTheirInputMayBeTheFolder) {
  Produce(Path("out"), "normals", {{"normals.exr", "n"}});
  OutputFolderOptions join = Command("integrate");
  join.joins = {"normals"};
  join.inputs = {Path("out")};
  {
    OutputFolder out(Path("out"), join);
    WriteTextFile(out.file("mesh.ply"), "m");
    out.Commit();
  }
  EXPECT_EQ(Read(Path("out/normals.exr")), "n");
  EXPECT_EQ(Read(Path("out/mesh.ply")), "m");
  const auto commands = nlohmann::json::parse(Read(Path("out/.iphong-manifest.json")))["commands"];
  EXPECT_TRUE(commands.contains("normals") && commands.contains("integrate"));
}

// `integrate DIR/normals.exr -o DIR`, as `integrate DIR -o DIR`: the joined command's file is
// an input read beside which the files are added (it was refused as "contains the input", while
// the help offers the normals' folder). A user's own file there stays an input it may not join,
// and the joined file is never replaced by the run that reads it.
TEST_F(OutputFolderTest, AJoinedCommandsFileMayBeTheInput) {
  Produce(Path("out"), "normals", {{"normals.exr", "n"}});
  Write(Path("out/mine.exr"), "user");
  OutputFolderOptions join = Command("integrate");
  join.joins = {"normals"};
  join.inputs = {Path("out/normals.exr")};
  {
    OutputFolder out(Path("out"), join);
    WriteTextFile(out.file("mesh.ply"), "m");
    out.Commit();
  }
  EXPECT_EQ(Read(Path("out/normals.exr")), "n");
  EXPECT_EQ(Read(Path("out/mesh.ply")), "m");
  join.overwrite = true;
  join.inputs = {Path("out/mine.exr")};
  EXPECT_NE(ErrorOf([&] { OutputFolder(Path("out"), join); }).find("contains the input"),
            std::string::npos);
  join.inputs = {Path("out/normals.exr")};
  EXPECT_NE(ErrorOf([&] {
              OutputFolder out(Path("out"), join);
              WriteTextFile(out.file("normals.exr"), "replaced");
              out.Commit();
            }).find("would replace its own input"),
            std::string::npos);
  EXPECT_EQ(Read(Path("out/normals.exr")), "n");
}

TEST_F(OutputFolderTest, OneWriterPerFolder) {
  Produce(Path("out"), "normals", {{"a.txt", "a"}});
  OutputFolder first(Path("out"), Command("normals", true));
  EXPECT_NE(ErrorOf([&] {
              OutputFolder(Path("out"), Command("normals", true));
            }).find("another iphong run is writing to this folder"),
            std::string::npos);
}

// The state a SIGKILL leaves between a commit's renames: the journal is written, one staged file
// has moved, the other and the new manifest have not. The next run that opens the folder (a
// reader, or a writer) finishes it: the new state, complete.
TEST_F(OutputFolderTest, CommitCutOffBetweenRenamesIsFinishedByTheNextRun) {
  Produce(Path("out"), "normals", {{"a.txt", "old a"}, {"b.txt", "old b"}, {"stale.txt", "s"}});
  Write(Path("out/notes.txt"), "user notes");
  const nlohmann::json old_manifest =
      nlohmann::json::parse(Read(Path("out/.iphong-manifest.json")));
  const std::string staging = ".iphong-partial-999999999-0";
  fs::create_directories(Path("out/" + staging));
  Write(Path("out/" + staging + "/b.txt"), "new b");
  nlohmann::json manifest = old_manifest;
  manifest["commands"]["normals"] = {{"a.txt", {{"size", 5}, {"mtime_ns", 1}}},
                                     {"b.txt", {{"size", 5}, {"mtime_ns", 2}}}};
  Write(Path("out/" + staging + "/.iphong-manifest.json"), manifest.dump());
  const auto stale = old_manifest["commands"]["normals"]["stale.txt"];
  nlohmann::json journal = {
      {"staging", staging},
      {"move", {"a.txt", "b.txt", ".iphong-manifest.json"}},
      {"remove",
       {{{"name", "stale.txt"}, {"size", stale["size"]}, {"mtime_ns", stale["mtime_ns"]}}}}};
  Write(Path("out/.iphong-commit.json"), journal.dump());
  Write(Path("out/a.txt.moved"), "new a");  // a.txt was moved before the kill:
  fs::rename(Path("out/a.txt.moved"), Path("out/a.txt"));

  FinishInterruptedCommit(Path("out"));
  EXPECT_EQ(Read(Path("out/a.txt")), "new a");
  EXPECT_EQ(Read(Path("out/b.txt")), "new b");
  EXPECT_FALSE(fs::exists(Path("out/stale.txt")));
  EXPECT_EQ(Read(Path("out/notes.txt")), "user notes");
  EXPECT_EQ(nlohmann::json::parse(Read(Path("out/.iphong-manifest.json"))), manifest);
  EXPECT_EQ(Names(Path("out")),
            (std::set<std::string>{"a.txt", "b.txt", "notes.txt", ".iphong-manifest.json"}));
  FinishInterruptedCommit(Path("out"));  // idempotent: nothing left to do
  EXPECT_EQ(Read(Path("out/b.txt")), "new b");
}

TEST_F(OutputFolderTest, StagingLeftByAKilledRunIsRemovedByTheNext) {
  fs::create_directories(Path(".out.iphong-partial-999999999-0"));
  Write(Path(".out.iphong-partial-999999999-0/x.txt"), "half");
  fs::create_directories(Path(".other.iphong-partial-999999999-0"));  // another target's
  Produce(Path("out"), "render", {{"x.txt", "whole"}});
  EXPECT_EQ(Names(dir_.string()),
            (std::set<std::string>{"out", ".other.iphong-partial-999999999-0"}));
  fs::create_directories(Path("out/.iphong-partial-999999999-1"));
  Produce(Path("out"), "render", {{"x.txt", "again"}}, true);
  EXPECT_EQ(Names(Path("out")), (std::set<std::string>{"x.txt", ".iphong-manifest.json"}));
}

TEST_F(OutputFolderTest, MessagesNameTheTargetNotTheStaging) {
  EXPECT_EQ(WithoutStagingNames("/d/.out.iphong-partial-12-3/normals.exr: cannot write: x"),
            "/d/out/normals.exr: cannot write: x");
  EXPECT_EQ(WithoutStagingNames("/d/out/.iphong-partial-12-3/sub/mesh.ply: no"),
            "/d/out/sub/mesh.ply: no");
  EXPECT_EQ(WithoutStagingNames("plain message"), "plain message");
}

TEST_F(OutputFolderTest, SingleFilesAreNewUnlessOverwrite) {
  auto write = [&](const std::string& text) {
    return [text](const std::string& temp) { WriteTextFile(temp, text); };
  };
  WriteSingleOutputFile("test", Path("map.png"), false, {}, write("one"));
  EXPECT_EQ(Read(Path("map.png")), "one");
  EXPECT_NE(ErrorOf([&] {
              WriteSingleOutputFile("test", Path("map.png"), false, {}, write("two"));
            }).find("exists; pass --overwrite"),
            std::string::npos);
  WriteSingleOutputFile("test", Path("map.png"), true, {}, write("three"));
  EXPECT_EQ(Read(Path("map.png")), "three");
  EXPECT_NE(ErrorOf([&] {
              WriteSingleOutputFile("test", Path("map.png"), true, {Path("map.png")},
                                    write("four"));
            }).find("is an input"),
            std::string::npos);
  EXPECT_THROW(WriteSingleOutputFile("test", Path("bad.png"), false, {},
                                     [](const std::string&) { throw OutputError("disk full"); }),
               OutputError);
  EXPECT_EQ(Names(dir_.string()), (std::set<std::string>{"map.png", ".iphong-manifest.json"}));
  // A missing folder is named as such (it was "DIR/.map.iphong-partial-…: cannot write: No such
  // file or directory"), and nothing is made.
  EXPECT_EQ(ErrorOf([&] {
              WriteSingleOutputFile("test", Path("nope/map.png"), false, {}, write("five"));
            }),
            Path("nope/map.png") + ": its folder " + Path("nope") +
                " does not exist; create it, or name a file in a folder that does");
  EXPECT_FALSE(fs::exists(Path("nope")));
}

// --overwrite replaces only what iphong wrote there and nobody changed since: a user's file of
// the same name (a photo named by mistake) stays, byte for byte.
TEST_F(OutputFolderTest, OverwriteReplacesOnlyIphongsOwnSingleFiles) {
  auto write = [&](const std::string& text) {
    return [text](const std::string& temp) { WriteTextFile(temp, text); };
  };
  WriteTextFile(Path("photo.png"), "the user's photo");
  EXPECT_NE(ErrorOf([&] {
              WriteSingleOutputFile("test", Path("photo.png"), true, {}, write("relit"));
            }).find("was not written by iphong"),
            std::string::npos);
  EXPECT_EQ(Read(Path("photo.png")), "the user's photo");
  // An iphong file the user edited since is theirs now.
  WriteSingleOutputFile("test", Path("relit.png"), false, {}, write("one"));
  WriteSingleOutputFile("other", Path("map.png"), false, {}, write("map"));
  std::filesystem::remove(Path("relit.png"));
  WriteTextFile(Path("relit.png"), "edited by the user");
  EXPECT_NE(ErrorOf([&] {
              WriteSingleOutputFile("test", Path("relit.png"), true, {}, write("two"));
            }).find("was not written by iphong"),
            std::string::npos);
  EXPECT_EQ(Read(Path("relit.png")), "edited by the user");
  // Both commands' files stay listed: each may be replaced.
  WriteSingleOutputFile("test", Path("map.png"), true, {}, write("map 2"));
  EXPECT_EQ(Read(Path("map.png")), "map 2");
}

}  // namespace
}  // namespace iphong::io
