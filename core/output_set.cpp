// Output files written all or nothing: temporaries, checks, backups, renames, rollback.
#include "core/output_set.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <climits>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <optional>
#include <set>

#include "core/error.h"
#include "core/hash.h"

namespace reliefsim {

namespace fs = std::filesystem;

namespace {

constexpr const char* kMarker = ".rs-";  // in every temporary and backup name
constexpr int kNameAttempts = 100;       // unique-name retries before giving up

std::string Quote(const std::string& s) { return "\"" + s + "\""; }

std::string ErrnoText(int e) { return std::strerror(e); }

/// Six characters from [a-z0-9] that differ between calls and processes. The names never
/// reach an output, so they need not be reproducible; O_EXCL / link() make them unique.
std::string RandomTag() {
    static std::atomic<uint64_t> counter{0};
    const uint64_t t =
        uint64_t(std::chrono::steady_clock::now().time_since_epoch().count());
    uint64_t h = Mix64(t ^ Mix64(uint64_t(::getpid()) << 20 ^ counter.fetch_add(1)));
    std::string tag(6, 'a');
    for (char& c : tag) {
        c = "abcdefghijklmnopqrstuvwxyz0123456789"[h % 36];
        h /= 36;
    }
    return tag;
}

/// Longest file name in `dir` (NAME_MAX, 255 on the usual file systems).
size_t NameMax(const fs::path& dir) {
    const long n = ::pathconf(dir.c_str(), _PC_NAME_MAX);
    return n > 0 ? size_t(n) : size_t(255);
}

/// A hidden name beside `name` in `dir`: ".NAME.rs-XXXXXX" + suffix, shortened so that it
/// fits the file system's limit.
fs::path SiblingName(const fs::path& dir, const std::string& name,
                     const std::string& suffix) {
    const std::string tag = std::string(kMarker) + RandomTag();
    const size_t limit = NameMax(dir);
    std::string keep = name;
    const size_t fixed = 1 + tag.size() + suffix.size();
    if (fixed + keep.size() > limit) keep.resize(limit > fixed ? limit - fixed : 0);
    return dir / ("." + keep + tag + suffix);
}

/// The destination's extension, kept on the temporary for writers that pick a format by
/// it; dropped when absurdly long.
std::string TempSuffix(const fs::path& target) {
    const std::string ext = target.extension().string();
    return ext.size() <= 16 ? ext : std::string();
}

}  // namespace

struct OutputSet::Entry {
    std::string path;         // as the caller gave it (for messages)
    fs::path target;          // lexically normal form (for operations)
    fs::path temp;            // the new file while it is written
    fs::path backup;          // the previous destination during Commit, if any
    bool movedAside = false;  // backup is the old file renamed, not a hard link
    bool existed = false;     // a regular file stood at target when Commit began
    mode_t oldMode = 0;       // its permission bits
};

namespace {

/// What stands at a destination and above it.
struct Inspection {
    std::vector<fs::path> missing;    // folders to create, outermost first
    fs::path existingDir;             // nearest existing ancestor (a directory)
    std::optional<struct stat> dest;  // lstat of the destination, when something is there
};

}  // namespace

OutputSet::OutputSet(std::string subject_) : subject(std::move(subject_)) {}

OutputSet::~OutputSet() {
    if (committed) return;
    for (const Entry& e : entries) ::unlink(e.temp.c_str());
}

namespace {

[[noreturn]] void Fail(const std::string& subject, const std::string& path,
                       const std::string& problem) {
    throw Error((subject.empty() ? std::string() : subject + ": ") + Quote(path) + ": " +
                problem);
}

Inspection Inspect(const std::string& subject, const std::string& path,
                   const fs::path& target) {
    Inspection r;
    if (target.filename().empty() || target.filename() == "." ||
        target.filename() == "..")
        Fail(subject, path, "names a folder; expected a file name");
    const std::string whole = target.string();
    if (whole.size() >= size_t(PATH_MAX))
        Fail(subject, path,
             "path is " + std::to_string(whole.size()) +
                 " bytes long, the system allows " + std::to_string(PATH_MAX - 1) +
                 "; nothing was written; choose a shorter path");
    // Walk up to the nearest existing ancestor.
    fs::path dir = target.parent_path();
    if (dir.empty()) dir = ".";
    for (;;) {
        struct stat st;
        if (::stat(dir.c_str(), &st) == 0) {
            if (!S_ISDIR(st.st_mode))
                Fail(subject, path,
                     Quote(dir.string()) +
                         " is not a folder; nothing was written; choose a path whose "
                         "parents are folders");
            break;
        }
        // Absent (ENOENT), below a file (ENOTDIR, reported at the file) or too long a
        // name (ENAMETOOLONG, reported below with the limit): keep walking up.
        const int e = errno;
        const fs::path up = dir.parent_path();
        if ((e != ENOENT && e != ENOTDIR && e != ENAMETOOLONG) || up == dir || dir == ".")
            Fail(subject, path,
                 "cannot reach folder " + Quote(dir.string()) + " (" + ErrnoText(e) +
                     "); nothing was written");
        r.missing.insert(r.missing.begin(), dir);
        dir = up.empty() ? fs::path(".") : up;
    }
    r.existingDir = dir;
    // A folder the process may not write to (permissions, a read-only mount) is found
    // here, before a run's work, not when its outputs are staged.
    if (::faccessat(AT_FDCWD, dir.c_str(), W_OK | X_OK, AT_EACCESS) != 0) {
        const int e = errno;
        if (e == EACCES || e == EPERM || e == EROFS)
            Fail(subject, path,
                 "cannot create a file in folder " + Quote(dir.string()) + " (" +
                     ErrnoText(e) + "); nothing was written");
    }
    // Every name that is still to be created must fit the file system's limit, checked
    // before anything exists (ENAMETOOLONG would otherwise strike halfway).
    const size_t nameMax = NameMax(dir);
    std::vector<fs::path> toCreate = r.missing;
    toCreate.push_back(target);
    for (const fs::path& p : toCreate) {
        const std::string name = p.filename().string();
        if (name.size() > nameMax)
            Fail(subject, path,
                 "name \"" + name.substr(0, 24) + "...\" is " +
                     std::to_string(name.size()) +
                     " bytes long, the file system allows " + std::to_string(nameMax) +
                     "; nothing was written; choose a shorter name");
    }
    if (r.missing.empty()) {
        struct stat st;
        if (::lstat(target.c_str(), &st) == 0) {
            if (!S_ISREG(st.st_mode)) {
                const char* what = S_ISDIR(st.st_mode)   ? "a folder"
                                   : S_ISLNK(st.st_mode) ? "a symbolic link"
                                                         : "not a regular file";
                Fail(subject, path,
                     std::string("is ") + what +
                         ", where an output file goes; nothing was written; move it away "
                         "or write elsewhere");
            }
            r.dest = st;
        } else if (errno != ENOENT) {
            Fail(subject, path,
                 std::string("cannot inspect the destination (") + ErrnoText(errno) +
                     "); nothing was written");
        }
    }
    return r;
}

}  // namespace

std::string OutputSet::Add(const std::string& path) {
    if (committed) throw Error(Quote(path) + ": output set already committed");
    const fs::path target = fs::path(path).lexically_normal();
    for (const Entry& e : entries)
        if (e.target == target) return e.temp.string();
    const Inspection in = Inspect(subject, path, target);
    const std::string suffix = TempSuffix(target);
    for (int attempt = 0; attempt < kNameAttempts; ++attempt) {
        const fs::path temp =
            SiblingName(in.existingDir, target.filename().string(), suffix);
        const int fd =
            ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd < 0) {
            if (errno == EEXIST) continue;
            Fail(subject, path,
                 "cannot create a file in folder " + Quote(in.existingDir.string()) +
                     " (" + ErrnoText(errno) + "); nothing was written");
        }
        ::close(fd);
        Entry e;
        e.path = path;
        e.target = target;
        e.temp = temp;
        entries.push_back(std::move(e));
        return temp.string();
    }
    Fail(subject, path,
         "cannot find a free temporary name in folder " + Quote(in.existingDir.string()));
}

void OutputSet::Write(const std::string& path, std::string_view bytes) {
    const std::string temp = Add(path);
    std::FILE* f = std::fopen(temp.c_str(), "wb");
    if (!f) Fail(subject, path, "cannot write (" + ErrnoText(errno) + ")");
    const size_t n = bytes.empty() ? 0 : std::fwrite(bytes.data(), 1, bytes.size(), f);
    const int writeErr = n == bytes.size() ? 0 : errno;
    const int closeErr = std::fclose(f) == 0 ? 0 : errno;
    if (writeErr || closeErr)
        Fail(subject, path,
             "cannot write (" + ErrnoText(writeErr ? writeErr : closeErr) +
                 "); nothing was written; check the free space");
}

std::string OutputSet::UserFacing(std::string message) const {
    for (const Entry& e : entries) {
        const std::string from = e.temp.string();
        for (size_t at = message.find(from); at != std::string::npos;
             at = message.find(from, at + e.path.size()))
            message.replace(at, from.size(), e.path);
    }
    return message;
}

std::vector<std::string> OutputSet::Destinations() const {
    std::vector<std::string> out;
    for (const Entry& e : entries) out.push_back(e.path);
    return out;
}

void OutputSet::SetRenameFaultForTesting(std::function<int(size_t)> fault) {
    renameFault = std::move(fault);
}

void OutputSet::Commit() {
    if (committed) throw Error("output set already committed");
    // 1. Check every destination before anything moves.
    std::vector<Inspection> checks;
    for (const Entry& e : entries) checks.push_back(Inspect(subject, e.path, e.target));

    std::vector<fs::path> created;  // folders made here, outermost first
    size_t nBackedUp = 0, nMoved = 0;
    // Undoes steps 2-4 (entries [0, nMoved) are in place, [0, nBackedUp) have backups)
    // and throws the error of `culprit`, with a note when a previous file could not be
    // put back.
    auto rollback = [&](const Entry& culprit, const std::string& problem) {
        std::string lost;
        for (size_t i = 0; i < entries.size(); ++i) {
            Entry& e = entries[i];
            const bool hasBackup = i < nBackedUp && !e.backup.empty();
            if (i < nMoved || (hasBackup && e.movedAside)) {
                if (hasBackup) {
                    if (::rename(e.backup.c_str(), e.target.c_str()) != 0)
                        lost += "; the previous " + Quote(e.path) +
                                " could not be put back (" + ErrnoText(errno) +
                                ") and is kept as " + Quote(e.backup.string());
                } else {
                    ::unlink(e.target.c_str());
                }
            } else if (hasBackup) {
                ::unlink(e.backup.c_str());
            }
            e.backup.clear();
        }
        for (auto it = created.rbegin(); it != created.rend(); ++it) ::rmdir(it->c_str());
        for (const Entry& e : entries) ::unlink(e.temp.c_str());
        committed = true;  // the temporaries are gone; the set is spent
        Fail(subject, culprit.path, problem + lost);
    };

    // 2. Missing folders, created as mkdir does (the umask decides their mode).
    for (size_t i = 0; i < entries.size(); ++i)
        for (const fs::path& dir : checks[i].missing) {
            if (::mkdir(dir.c_str(), 0777) == 0) {
                created.push_back(dir);
                continue;
            }
            const int err = errno;
            struct stat st;
            if (err == EEXIST && ::stat(dir.c_str(), &st) == 0 && S_ISDIR(st.st_mode))
                continue;  // made by an earlier destination, or meanwhile by someone else
            rollback(entries[i], "cannot create folder " + Quote(dir.string()) + " (" +
                                     ErrnoText(err) + "); nothing was written");
        }

    // 3. Keep every file that is about to be replaced.
    for (size_t i = 0; i < entries.size(); ++i, nBackedUp = i) {
        Entry& e = entries[i];
        e.existed = checks[i].dest.has_value();
        if (!e.existed) continue;
        e.oldMode = checks[i].dest->st_mode & 07777;
        const fs::path dir = e.target.has_parent_path() ? e.target.parent_path() : ".";
        int err = 0;
        for (int attempt = 0; attempt < kNameAttempts; ++attempt) {
            const fs::path b = SiblingName(dir, e.target.filename().string(), ".bak");
            if (::link(e.target.c_str(), b.c_str()) == 0) {
                e.backup = b;
                break;
            }
            err = errno;
            if (err == EEXIST) continue;
            // No hard links here: reserve a name, then move the file onto it.
            const int fd =
                ::open(b.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
            if (fd < 0) {
                err = errno;
                if (err == EEXIST) continue;
                break;
            }
            ::close(fd);
            if (::rename(e.target.c_str(), b.c_str()) == 0) {
                e.backup = b;
                e.movedAside = true;
            } else {
                err = errno;
                ::unlink(b.c_str());
            }
            break;
        }
        if (e.backup.empty()) {
            nBackedUp = i;
            rollback(e, "cannot keep the previous file while replacing it (" +
                            ErrnoText(err) + "); nothing was changed");
        }
    }
    nBackedUp = entries.size();

    // 4. The new files into place.
    for (size_t i = 0; i < entries.size(); ++i, nMoved = i) {
        Entry& e = entries[i];
        if (e.existed) ::chmod(e.temp.c_str(), e.oldMode);
        int err = renameFault ? renameFault(i) : 0;
        if (err == 0 && ::rename(e.temp.c_str(), e.target.c_str()) != 0) err = errno;
        if (err != 0) {
            nMoved = i;
            rollback(e, "cannot move the new file into place (" + ErrnoText(err) +
                            "); nothing was changed");
        }
    }

    // 5. Done: drop the backups.
    for (Entry& e : entries)
        if (!e.backup.empty()) ::unlink(e.backup.c_str());
    committed = true;
}

void CheckOutputDestination(const std::string& path, const std::string& subject) {
    Inspect(subject, path, fs::path(path).lexically_normal());
}

void WriteFileAtomically(const std::string& path, std::string_view bytes,
                         const std::string& subject) {
    OutputSet set(subject);
    set.Write(path, bytes);
    set.Commit();
}

}  // namespace reliefsim
