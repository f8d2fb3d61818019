// Heap allocation counter for tests (see alloc_counter.cpp).
#pragma once

namespace alloc_counter {
bool hooks_active();      // false under AddressSanitizer (it owns malloc)
void arm();               // start counting from zero
unsigned long disarm();   // stop; returns allocations seen while armed
}  // namespace alloc_counter
