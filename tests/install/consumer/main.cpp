// A user's program built against an installed vtex: it must compile, link and run.
#include <vtex/core/error.h>
#include <vtex/core/version.h>

#include <cstdio>
#include <cstring>

int main() {
    const vtex::InputError error("in.obj", "no faces");
    if (std::strcmp(error.what(), "in.obj: no faces") != 0) return 1;
    std::printf("linked against vtex %s\n", vtex::kVersion);
    return 0;
}
