//! The process's allocator settings (glibc on Linux only; elsewhere nothing).
//!
//! glibc serves an allocation from its heap arenas unless it is larger than a threshold
//! that starts at 128 KiB and rises, up to 32 MiB, to the size of each large block freed.
//! A run frees and allocates arrays of a few MiB to a hundred MiB in turn (a level's
//! fields, the links, the sweep's arrays), so after the first frees most of them came
//! from the arenas, where freed space stays resident and fragments: tm_cycloidal.ply's
//! whole run held 1896 MiB resident for a heap that peaked at 1.55 GiB (heaptrack). A
//! fixed threshold maps every larger array apart and returns it to the system when it
//! is freed (`/usr/bin/time -f %M necklace loops MESH -q --json`, glibc's
//! `MALLOC_MMAP_THRESHOLD_`): 1 MiB gave 1781 MiB, 4 MiB 1803 MiB and 16 MiB 1817 MiB
//! on tm_cycloidal; but each mapped array is paged in afresh, and 1 MiB cost the cow and
//! th_65004 2–3 % of their time, where 4 MiB leaves their arrays (mostly smaller) on
//! the arenas: the cow 7.43 → 7.51 s over three pairs.

/// Allocations of at least this many bytes are mapped apart (and unmapped when freed).
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const MMAP_THRESHOLD: libc::c_int = 4 << 20;

/// Fix glibc's mmap threshold at [`MMAP_THRESHOLD`] (which also stops it from rising).
#[cfg(all(target_os = "linux", target_env = "gnu"))]
pub fn configure() {
    // SAFETY: `mallopt` only sets an allocator parameter; it is called before any
    // thread is started.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, MMAP_THRESHOLD);
    }
}

/// Nothing to set outside glibc.
#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
pub fn configure() {}
