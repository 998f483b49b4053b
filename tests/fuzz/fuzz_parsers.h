// Shared by the fuzz target and its bounded driver: how many parsers the first byte picks from.
#pragma once

constexpr int kFuzzParsers = 11;
