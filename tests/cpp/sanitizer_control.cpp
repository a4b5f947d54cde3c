// Negative control of the sanitizer build (ALGID_SANITIZE=ON): each mode commits one error that
// AddressSanitizer or UndefinedBehaviorSanitizer must report and abort on. A run that exits 0
// means the sanitizers are not active and the sanitized test results prove nothing.
#include <climits>
#include <cstdio>
#include <cstring>
#include <vector>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::printf("usage: sanitizer_control heap-overflow|signed-overflow\n");
    return 2;
  }
  // The index and the addend come from the command line so the compiler cannot fold them.
  const int offset = static_cast<int>(std::strlen(argv[1]) > 0);
  if (std::strcmp(argv[1], "heap-overflow") == 0) {
    std::vector<double> v(4, 1.0);
    const double* data = v.data();
    std::printf("read past the end: %g\n", data[3 + offset]);
  } else if (std::strcmp(argv[1], "signed-overflow") == 0) {
    const int big = INT_MAX - 1 + offset;
    std::printf("INT_MAX + 1 = %d\n", big + offset);
  } else {
    return 2;
  }
  std::printf("not reported: the sanitizers are not active\n");
  return 0;
}
