// liftd entry point (placeholder until the foundation daemon lands).
#include <cstdio>

int main() {
  std::puts("liftd " "0.1.0");
  return 0;
}
