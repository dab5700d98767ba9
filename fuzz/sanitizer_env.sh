# Sanitizer settings of the sanitizer job and the fuzzers (sourced by scripts/sanitize and fuzz/run.sh). Each
# suppression names a third-party report and why it is not ours: see fuzz/*.supp.
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
# detect_leaks=0: LeakSanitizer stops every thread of a process to scan it, and with TBB's workers exiting that
# sometimes ends in "LeakSanitizer has encountered a fatal error" (seen once in 640 tests): leaks are checked where it
# matters, by scripts/sanitize running the soak test (1,000 renders in one process) with detect_leaks=1 on its own.
# new_delete_type_mismatch=0: OpenImageIO's
# TextureSystem::destroy deletes through a base pointer of another size (seen at every scene load before the texture
# system became process-wide; ASan cannot suppress that report by library, so the check is off for the process).
export ASAN_OPTIONS="detect_leaks=0:new_delete_type_mismatch=0:abort_on_error=1:symbolize=1:detect_odr_violation=0"
export LSAN_OPTIONS="suppressions=$HERE/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="suppressions=$HERE/ubsan.supp:print_stacktrace=1:halt_on_error=1"
