// SPDX-License-Identifier: MIT
#include <cstdio>
int main() { std::puts("nfield: under construction"); return 0; }
