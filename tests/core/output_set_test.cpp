// OutputSet: all-or-nothing output files (checks before the first move, rollback, umask,
// names, temporaries never left behind, errors naming the user's path).
#include "core/output_set.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <string>

#include "core/error.h"
#include "tests/common/test_files.h"

using namespace reliefsim;
namespace fs = std::filesystem;
using reliefsim::testing::ExpectNoLeftovers;
using reliefsim::testing::Slurp;
using reliefsim::testing::Snapshot;
using reliefsim::testing::WriteBytes;

namespace {

fs::path Scratch() { return reliefsim::testing::Scratch("rs_output_set_"); }

/// Everything under `dir`: per relative path, its type, mode, size, mtime, inode and

std::string ErrorOf(const std::function<void()>& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    }
    ADD_FAILURE() << "expected Error";
    return {};
}

/// Sets the umask for the scope.
struct UmaskScope {
    mode_t old;
    explicit UmaskScope(mode_t m) : old(::umask(m)) {}
    ~UmaskScope() { ::umask(old); }
};

mode_t ModeOf(const fs::path& p) {
    struct stat st;
    EXPECT_EQ(::stat(p.c_str(), &st), 0) << p;
    return st.st_mode & 07777;
}

}  // namespace

TEST(OutputSet, CommitReplacesEveryFileAndKeepsOthers) {
    const fs::path d = Scratch();
    WriteBytes(d / "a.txt", "old a");
    WriteBytes(d / "notes.txt", "mine");
    OutputSet set("--out");
    set.Write((d / "a.txt").string(), "new a");
    set.Write((d / "b.txt").string(), "new b");
    const std::string temp = set.Add((d / "c.bin").string());
    EXPECT_EQ(fs::path(temp).parent_path(), d);
    EXPECT_EQ(fs::path(temp).extension(), ".bin");  // writers that pick a format by it
    EXPECT_NE(temp.find(".rs-"), std::string::npos);
    WriteBytes(temp, "new c");
    EXPECT_EQ(Slurp(d / "a.txt"), "old a");  // nothing visible before Commit
    EXPECT_FALSE(fs::exists(d / "b.txt"));
    set.Commit();
    EXPECT_EQ(Slurp(d / "a.txt"), "new a");
    EXPECT_EQ(Slurp(d / "b.txt"), "new b");
    EXPECT_EQ(Slurp(d / "c.bin"), "new c");
    EXPECT_EQ(Slurp(d / "notes.txt"), "mine");
    EXPECT_EQ(fs::hard_link_count(d / "a.txt"), 1u);  // the backup link is gone
    ExpectNoLeftovers(d);
    EXPECT_THROW(set.Commit(), Error);
}

TEST(OutputSet, SameDestinationTwiceIsOneEntry) {
    const fs::path d = Scratch();
    OutputSet set;
    const std::string a = set.Add((d / "x.png").string());
    EXPECT_EQ(set.Add((d / "." / "x.png").string()), a);
    EXPECT_EQ(set.Destinations().size(), 1u);
}

TEST(OutputSet, DirectoryInTheWayIsRefusedBeforeAnythingMoves) {
    const fs::path d = Scratch();
    WriteBytes(d / "a.txt", "old a");
    fs::create_directory(d / "b.txt");
    WriteBytes(d / "b.txt" / "inside", "kept");
    const auto before = Snapshot(d);
    {
        // Seen at Add: the set is abandoned, its temporaries removed.
        OutputSet set("--out \"d\"");
        set.Write((d / "a.txt").string(), "new a");
        const std::string msg = ErrorOf([&] { set.Add((d / "b.txt").string()); });
        EXPECT_NE(msg.find("--out \"d\": "), std::string::npos) << msg;
        EXPECT_NE(msg.find((d / "b.txt").string() + "\": is a folder"), std::string::npos)
            << msg;
        EXPECT_EQ(msg.find('\n'), std::string::npos);
        EXPECT_EQ(msg.find(".rs-"), std::string::npos) << msg;
    }
    EXPECT_EQ(Snapshot(d), before);
    {
        // Appearing after Add: refused at Commit, before the first rename.
        fs::remove_all(d / "b.txt");
        OutputSet set;
        set.Write((d / "a.txt").string(), "new a");
        set.Write((d / "b.txt").string(), "new b");
        fs::create_directory(d / "b.txt");
        WriteBytes(d / "b.txt" / "inside", "kept");
        EXPECT_THROW(set.Commit(), Error);
        EXPECT_EQ(Slurp(d / "a.txt"), "old a");
        EXPECT_EQ(Slurp(d / "b.txt" / "inside"), "kept");
    }
    ExpectNoLeftovers(d);
}

TEST(OutputSet, SymlinkAndOtherEntriesAreRefused) {
    const fs::path d = Scratch();
    WriteBytes(d / "target.txt", "theirs");
    fs::create_symlink(d / "target.txt", d / "link.txt");
    ASSERT_EQ(::mkfifo((d / "fifo").c_str(), 0600), 0);
    const auto before = Snapshot(d);
    OutputSet set;
    EXPECT_NE(ErrorOf([&] { set.Add((d / "link.txt").string()); }).find("symbolic link"),
              std::string::npos);
    EXPECT_NE(ErrorOf([&] { set.Add((d / "fifo").string()); }).find("not a regular file"),
              std::string::npos);
    EXPECT_EQ(Snapshot(d), before);
}

TEST(OutputSet, FailedRenameRestoresEveryPreviousFile) {
    const fs::path d = Scratch();
    for (const char* n : {"a.png", "b.exr", "c.json"})
        WriteBytes(d / n, std::string("old ") + n);
    WriteBytes(d / "notes.txt", "mine");
    ::chmod((d / "b.exr").c_str(), 0640);
    const auto before = Snapshot(d);
    for (size_t failAt = 0; failAt < 3; ++failAt) {
        OutputSet set("--out \"o\"");
        for (const char* n : {"a.png", "b.exr", "c.json", "d.new"})
            set.Write((d / n).string(), std::string("new ") + n);
        set.SetRenameFaultForTesting([&](size_t i) { return i == failAt ? EIO : 0; });
        const std::string msg = ErrorOf([&] { set.Commit(); });
        const char* names[] = {"a.png", "b.exr", "c.json"};
        EXPECT_NE(msg.find((d / names[failAt]).string()), std::string::npos) << msg;
        EXPECT_NE(msg.find("nothing was changed"), std::string::npos) << msg;
        EXPECT_EQ(msg.find(".rs-"), std::string::npos) << msg;
        EXPECT_EQ(Snapshot(d), before) << "failing at " << failAt;  // same inodes, times
    }
    ExpectNoLeftovers(d);
}

TEST(OutputSet, RollbackRemovesTheFoldersItCreated) {
    const fs::path d = Scratch();
    WriteBytes(d / "mine.txt", "mine");
    const auto before = Snapshot(d);
    OutputSet set;
    set.Write((d / "new" / "a" / "b" / "x.txt").string(), "x");
    set.Write((d / "new" / "c" / "y.txt").string(), "y");
    EXPECT_FALSE(
        fs::exists(d / "new"));  // temporaries wait in the nearest existing folder
    set.SetRenameFaultForTesting([](size_t i) { return i == 1 ? ENOSPC : 0; });
    EXPECT_THROW(set.Commit(), Error);
    EXPECT_EQ(Snapshot(d), before);
}

TEST(OutputSet, MissingFoldersAreCreatedAtCommitAsTheUmaskSays) {
    const fs::path d = Scratch();
    for (const mode_t mask : {mode_t(022), mode_t(077), mode_t(002)}) {
        UmaskScope scope(mask);
        const fs::path top = d / ("m" + std::to_string(mask));
        OutputSet set;
        set.Write((top / "sub" / "f.txt").string(), "f");
        EXPECT_FALSE(fs::exists(top));
        set.Commit();
        EXPECT_EQ(ModeOf(top), 0777 & ~mask);
        EXPECT_EQ(ModeOf(top / "sub"), 0777 & ~mask);
        EXPECT_EQ(ModeOf(top / "sub" / "f.txt"), 0666 & ~mask);
    }
    ExpectNoLeftovers(d);
}

TEST(OutputSet, ReplacedFileKeepsItsPermissionBits) {
    const fs::path d = Scratch();
    WriteBytes(d / "f.txt", "old");
    ::chmod((d / "f.txt").c_str(), 0640);
    WriteFileAtomically((d / "f.txt").string(), "new");
    EXPECT_EQ(Slurp(d / "f.txt"), "new");
    EXPECT_EQ(ModeOf(d / "f.txt"), mode_t(0640));
}

TEST(OutputSet, TooLongNamesAreRefusedBeforeAnythingIsCreated) {
    const fs::path d = Scratch();
    const std::string longName(300, 'x');
    const auto before = Snapshot(d);
    OutputSet set("--out");
    const std::string msg =
        ErrorOf([&] { set.Add((d / "new" / longName / "color.png").string()); });
    EXPECT_NE(msg.find("300 bytes long"), std::string::npos) << msg;
    EXPECT_THROW(set.Add((d / (longName + ".png")).string()), Error);
    EXPECT_EQ(Snapshot(d), before);
    // A name just inside the limit works: the temporary's name is shortened to fit.
    const std::string name(250, 'y');
    WriteFileAtomically((d / (name + ".txt")).string(), "ok");
    EXPECT_EQ(Slurp(d / (name + ".txt")), "ok");
    ExpectNoLeftovers(d);
}

TEST(OutputSet, ParentThatIsAFileIsRefused) {
    const fs::path d = Scratch();
    WriteBytes(d / "file", "x");
    const auto before = Snapshot(d);
    const std::string msg = ErrorOf([&] {
        WriteFileAtomically((d / "file" / "sub" / "f.txt").string(), "f", "--out");
    });
    EXPECT_NE(msg.find("\"" + (d / "file").string() + "\" is not a folder"),
              std::string::npos)
        << msg;
    EXPECT_EQ(Snapshot(d), before);
}

TEST(OutputSet, AbandonedSetRemovesItsTemporaries) {
    const fs::path d = Scratch();
    {
        OutputSet set;
        set.Write((d / "a.txt").string(), "a");
        set.Write((d / "new" / "b.txt").string(), "b");
    }
    EXPECT_TRUE(fs::is_empty(d));
}

TEST(OutputSet, UserFacingNamesTheDestination) {
    const fs::path d = Scratch();
    OutputSet set;
    const std::string temp = set.Add((d / "r.exr").string());
    EXPECT_EQ(set.UserFacing("cannot open \"" + temp + "\" (disk full)"),
              "cannot open \"" + (d / "r.exr").string() + "\" (disk full)");
}

TEST(OutputSet, EmptyOrFolderNamesAreRefused) {
    OutputSet set;
    EXPECT_THROW(set.Add(""), Error);
    EXPECT_THROW(set.Add("a/.."), Error);
}

TEST(OutputSet, FolderWithoutWritePermissionIsRefusedByTheCheck) {
    const fs::path d = Scratch();
    fs::create_directories(d / "ro");
    fs::create_directories(d / "rw");
    ::chmod(d.c_str(), 0755);
    ::chmod((d / "ro").c_str(), 0555);
    ::chmod((d / "rw").c_str(), 0777);
    const auto before = Snapshot(d);
    // Root may write anywhere, so the checks run in a child as an unprivileged user. The
    // child's exit code: 3 = the error named the folder, 4 = another error, 0 = passed.
    const auto check = [&](const fs::path& out) {
        if (::geteuid() == 0 && (::setgid(65534) != 0 || ::setuid(65534) != 0))
            std::_Exit(2);
        try {
            CheckOutputDestination(out.string(), "--out");
        } catch (const Error& e) {
            std::fprintf(stderr, "%s\n", e.what());
            const std::string msg = e.what();
            std::_Exit(msg.find("cannot create a file in folder \"" +
                                (d / "ro").string() + "\"") != std::string::npos
                           ? 3
                           : 4);
        }
        std::_Exit(0);
    };
    EXPECT_EXIT(check(d / "ro" / "a.exr"), ::testing::ExitedWithCode(3),
                "nothing was written");
    // A missing folder that would be created inside it: the same folder is named.
    EXPECT_EXIT(check(d / "ro" / "sub" / "a.exr"), ::testing::ExitedWithCode(3), "");
    // A folder it may write to passes.
    EXPECT_EXIT(check(d / "rw" / "a.exr"), ::testing::ExitedWithCode(0), "");
    EXPECT_EQ(Snapshot(d), before);
    ::chmod((d / "ro").c_str(), 0755);
}
