// Output files written all or nothing: unique temporaries beside each destination, every
// destination checked before the first rename, and a rollback that restores what was
// there.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace reliefsim {

/// A set of output files that replace their destinations all or nothing.
///
/// Add(path) checks the destination and returns a temporary to write the new file to. The
/// temporary is created empty (mode 0666 & ~umask), under a unique name
/// ".NAME.rs-XXXXXX.EXT" (the destination's extension kept, so that writers choosing a
/// format by extension still do), in the destination's folder or, when that folder does
/// not exist yet, in its nearest existing ancestor (same file system, so renames are
/// atomic). Commit() then, in order:
///  1. checks every destination again: each file name within the file system's limit,
///     every existing ancestor a directory, nothing but a regular file at the destination
///     (a directory, symbolic link, FIFO... standing there is refused). Any problem:
///     Error, and nothing at the destinations has changed;
///  2. creates the missing folders (mode 0777 & ~umask, as mkdir does);
///  3. keeps every existing destination as a hidden backup beside it (a hard link, or a
///     rename where the file system has none);
///  4. renames each temporary onto its destination, with the permission bits of the file
///     it replaces;
///  5. deletes the backups.
/// When step 2, 3 or 4 fails, everything done so far is undone: replaced files are
/// restored from their backups, new files removed, and the folders this commit created
/// removed. Entries of those folders that are not destinations are never touched.
///
/// Errors are reliefsim::Error, one line, "SUBJECT: "PATH": problem; hint", naming the
/// destination the caller gave, never a temporary (UserFacing() rewrites third-party
/// messages that mention one). The destructor removes the temporaries of a set that was
/// not committed, so an exception anywhere leaves no file behind. Not thread-safe; one
/// set per output operation.
class OutputSet {
  public:
    /// `subject` prefixes every error (e.g. `--out "renders/a"`); may be empty.
    explicit OutputSet(std::string subject = {});
    ~OutputSet();
    OutputSet(const OutputSet&) = delete;
    OutputSet& operator=(const OutputSet&) = delete;

    /// Registers destination `path` (a file) and returns the path of its temporary.
    /// Adding the same destination again returns the same temporary. Throws Error when
    /// the destination cannot receive a file (see Commit() step 1) or the temporary
    /// cannot be created; nothing is created then.
    std::string Add(const std::string& path);

    /// Add(path), then writes `bytes` to the temporary. Throws Error naming `path`.
    void Write(const std::string& path, std::string_view bytes);

    /// Moves every added file into place, all or nothing (see the class comment). A set
    /// is committed once; later calls to Add or Commit are errors.
    void Commit();

    /// `message` with every temporary's path replaced by its destination's.
    std::string UserFacing(std::string message) const;

    /// Destinations added so far, in order.
    std::vector<std::string> Destinations() const;

    /// For tests: called before destination `index` is renamed into place; a non-zero
    /// return is taken as the errno of a failed rename (so the rollback runs).
    void SetRenameFaultForTesting(std::function<int(size_t index)> fault);

  private:
    struct Entry;
    std::string subject;
    std::vector<Entry> entries;
    bool committed = false;
    std::function<int(size_t)> renameFault;
};

/// Checks, creating nothing, that `path` could receive an output file: exactly the checks
/// OutputSet::Add makes (a file name, path and names within the system's limits, parents
/// that are folders or can be created, nothing but a regular file at the destination).
/// For validating a run's outputs before its work starts. Throws Error prefixed with
/// `subject` when given.
void CheckOutputDestination(const std::string& path, const std::string& subject = {});

/// Writes `bytes` to `path` through a one-file OutputSet: the file is either complete or
/// untouched. Throws Error (prefixed with `subject` when given).
void WriteFileAtomically(const std::string& path, std::string_view bytes,
                         const std::string& subject = {});

}  // namespace reliefsim
