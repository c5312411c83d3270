// liod-eval: compares an estimated trajectory with ground truth. See README.md for the definitions.
#include <iostream>

#include "liod/eval/cli.hpp"

int main(int argc, char** argv) { return liod::eval::run_cli(argc, argv, std::cout, std::cerr); }
