// ffcube-view3d IN OUT: View3D's own command line, for a pipeline whose VIEW3D_EXE names an
// executable (docs/urban.md). It replaces itself by the ffcube binary that lies beside it (the
// build puts both in the build directory, `cmake --install` both in bin/), as
// `ffcube view3d IN OUT`: the same process, bytes, messages and exit codes.
//
// Why a program of its own rather than a link to ffcube dispatching on argv[0]: pipelines resolve
// the path they are given (uDALES' resolve_view3d_exe calls Path.resolve(), which follows a
// symbolic link to `ffcube`, so argv[0] would no longer say view3d), and a hard link goes stale
// when ffcube is linked again. This file links nothing of ffcube's (a second executable with every
// layer would double the link), and /proc/self/exe names this file's real directory however it
// was started (through a link, from PATH, by a relative path).
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

int main(int argc, char** argv) {
    char self[PATH_MAX];
    const ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
    if (n <= 0) {
        std::fprintf(stderr, "ffcube-view3d: error: cannot find its own path (/proc/self/exe): %s\n", std::strerror(errno));
        return 70;
    }
    std::string path(self, static_cast<std::size_t>(n));
    path = path.substr(0, path.rfind('/') + 1) + "ffcube";
    std::vector<char*> args{const_cast<char*>("ffcube"), const_cast<char*>("view3d")};
    for (int i = 1; i < argc; ++i) args.push_back(argv[i]);
    args.push_back(nullptr);
    execv(path.c_str(), args.data());
    std::fprintf(stderr, "ffcube-view3d: error: cannot run %s (ffcube-view3d runs the ffcube beside it): %s\n", path.c_str(),
                 std::strerror(errno));
    return 70;
}
