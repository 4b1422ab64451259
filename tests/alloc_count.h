/* Allocation counting shared by the test files (the interposed malloc,
 * calloc and realloc live in test_invariants.c; the whole test binary uses
 * them). Count only while cd_test_counting is set. Under AddressSanitizer,
 * which owns malloc, CD_COUNT_ALLOC is 0 and counting tests skip. */
#ifndef CD_TEST_ALLOC_COUNT_H
#define CD_TEST_ALLOC_COUNT_H

#if defined(__SANITIZE_ADDRESS__)
#define CD_COUNT_ALLOC 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define CD_COUNT_ALLOC 0
#endif
#endif
#ifndef CD_COUNT_ALLOC
#define CD_COUNT_ALLOC 1
#endif

extern volatile int cd_test_counting;
extern volatile long cd_test_nalloc;

#endif
