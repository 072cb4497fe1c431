// Seed corpora for the host importer fuzzers: the tests generate small
// valid files rather than carry third-party ones. Called from
// LLVMFuzzerInitialize: when the corpus directory (libFuzzer's last
// non-option argument) exists and is empty, `seed` writes files into it.
#pragma once
#include <filesystem>
#include <system_error>

namespace vds::test {

template <class Seed>
void seed_corpus_if_empty(int argc, char** argv, Seed seed) {
  for (int i = argc - 1; i > 0; --i) {
    const char* a = argv[i];
    if (a[0] == '-') continue;
    std::error_code ec;
    if (std::filesystem::is_directory(a, ec) && std::filesystem::is_empty(a, ec)) seed(std::filesystem::path(a));
    return;
  }
}

}  // namespace vds::test
