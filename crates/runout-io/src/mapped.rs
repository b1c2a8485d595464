//! Files mapped into memory instead of read (issue 18), with a guard against their shortening:
//! a text recording's data rows (the parse workers read the file's pages where the kernel keeps
//! them, without the copy of every byte into a buffer that `read` makes) and a job's temporary
//! spill read back (`runout::spill`).
//!
//! Off unless the process opts in with [`allow_mapped_files`], and only on Linux. A mapped file
//! that another process shortens while it is read makes the kernel send `SIGBUS` at the next
//! access past its new end, which would kill the process. The opt-in installs a handler that
//! puts a page of zeros where the access failed, inside a mapping of this module only (other
//! faults go to the handler installed before); the reader of the map then stops at the zeros or
//! goes on, and [`MappedFile::shortened`] reports the file as shortened (a clear error with
//! both lengths, never a value from a partial file).
//!
//! Memory stays bounded when the reader releases what it has read ([`MappedFile::release`]):
//! the pages leave the process (they stay in the kernel's page cache), so the resident size
//! does not grow with the file.

use std::fs::File;
use std::sync::atomic::{AtomicBool, Ordering};

static ALLOWED: AtomicBool = AtomicBool::new(false);

/// Let [`MappedFile::new`] map files (process-wide; Linux only, elsewhere nothing changes): the
/// text recordings opened by [`RecordingReader::open`](crate::recording::RecordingReader::open)
/// from then on, and a job's spill. Installs a `SIGBUS` handler for the mappings (module docs);
/// a fault outside them goes to the handler installed before.
///
/// # Safety
/// The caller guarantees that no mapped file is written in place by another process while it
/// is read: readers hold the mapped bytes as immutable. (A file shortened while it is read is
/// reported by [`MappedFile::shortened`].)
///
/// ```
/// // a command-line program, as `runout` does at start:
/// unsafe { runout_io::mapped::allow_mapped_files() };
/// assert_eq!(runout_io::mapped::allowed(), cfg!(target_os = "linux"));
/// ```
pub unsafe fn allow_mapped_files() {
    #[cfg(target_os = "linux")]
    if guard::install() {
        ALLOWED.store(true, Ordering::Relaxed);
    }
}

/// Whether [`allow_mapped_files`] has taken effect.
pub fn allowed() -> bool {
    ALLOWED.load(Ordering::Relaxed)
}

/// A file mapped read-only from a byte offset to its end, guarded against its shortening.
///
/// ```
/// # unsafe { runout_io::mapped::allow_mapped_files() };
/// use std::io::Write;
/// let mut f = tempfile::tempfile().unwrap();
/// f.write_all(b"header\n1,2\n3,4\n").unwrap();
/// let m = runout_io::mapped::MappedFile::new(f, 7);
/// assert_eq!(m.is_some(), cfg!(target_os = "linux")); // elsewhere: read the file instead
/// if let Some(m) = m {
///     assert_eq!(m.bytes(), b"1,2\n3,4\n");
///     assert!(m.shortened().is_none());
/// }
/// ```
#[derive(Debug)]
pub struct MappedFile {
    map: memmap2::Mmap,
    file: File,
    /// The file's length when it was mapped (bytes).
    length: u64,
    #[cfg(target_os = "linux")]
    slot: guard::Slot,
}

impl MappedFile {
    /// Map `file` from byte `offset` to its end. `None` when mapping is not allowed
    /// ([`allow_mapped_files`]), there is nothing to map, or the mapping or its guard is not
    /// available (the caller reads the file instead).
    pub fn new(file: File, offset: u64) -> Option<Self> {
        if !allowed() {
            return None;
        }
        let meta = file.metadata().ok()?;
        if !meta.is_file() || meta.len() <= offset {
            return None;
        }
        // SAFETY: the process opted in (`allow_mapped_files`): the file is not written in place
        // while it is read, and a SIGBUS from its shortening is handled (`guard`).
        let map = unsafe { memmap2::MmapOptions::new().offset(offset).map(&file) }.ok()?;
        #[cfg(target_os = "linux")]
        let slot = guard::Slot::register(map.as_ptr() as usize, map.len())?;
        Some(MappedFile {
            length: offset + map.len() as u64,
            map,
            file,
            #[cfg(target_os = "linux")]
            slot,
        })
    }

    /// The mapped bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.map
    }

    /// Release the pages of `bytes()[a..b]` from the process (its resident size) once they
    /// have been read; a page shared with bytes still to read may be released too and is read
    /// again from the page cache when they are.
    pub fn release(&self, a: usize, b: usize) {
        if b > a && b <= self.map.len() {
            // SAFETY: a shared read-only file mapping: released pages are read again from the
            // file's page cache on the next access, with the same bytes (unlike a private or
            // anonymous mapping, whose pages would come back zeroed).
            unsafe {
                self.map
                    .unchecked_advise_range(memmap2::UncheckedAdvice::DontNeed, a, b - a)
                    .ok();
            }
        }
    }

    /// The error when the file is now shorter than when it was mapped, or a page of the map
    /// had to be replaced by zeros: what was read from it after its new end is not the file.
    pub fn shortened(&self) -> Option<std::io::Error> {
        let now = self.file.metadata().map_or(0, |m| m.len());
        #[cfg(target_os = "linux")]
        let faulted = self.slot.faulted();
        #[cfg(not(target_os = "linux"))]
        let faulted = false;
        (now < self.length || faulted).then(|| {
            std::io::Error::other(format!(
                "the file was shortened while it was being read ({} bytes when opened, {now} now): \
                 its end was no longer there to read; run again once the file is complete",
                self.length
            ))
        })
    }
}

/// The `SIGBUS` handler for the mappings (module docs).
#[cfg(target_os = "linux")]
mod guard {
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
    use std::sync::OnceLock;

    /// Mappings that may be guarded at once (a reader maps one file at a time).
    const SLOTS: usize = 64;

    /// Start (0: free) and length of each guarded mapping, and whether it faulted. A slot is
    /// filled length first and freed start first, so that the handler never sees a start with
    /// another mapping's length.
    struct Range {
        start: AtomicUsize,
        len: AtomicUsize,
        faulted: AtomicBool,
    }

    static RANGES: [Range; SLOTS] = [const {
        Range {
            start: AtomicUsize::new(0),
            len: AtomicUsize::new(0),
            faulted: AtomicBool::new(false),
        }
    }; SLOTS];

    /// The disposition of SIGBUS before ours, and the page size.
    static BEFORE: OnceLock<(libc::sigaction, usize)> = OnceLock::new();

    /// Install the handler once; false if it could not be installed.
    pub fn install() -> bool {
        BEFORE
            .get_or_init(|| {
                // SAFETY: plain libc calls on zero-initialised C structs
                unsafe {
                    let page = usize::try_from(libc::sysconf(libc::_SC_PAGESIZE)).unwrap_or(0);
                    let mut ours: libc::sigaction = std::mem::zeroed();
                    let handler: extern "C" fn(
                        libc::c_int,
                        *mut libc::siginfo_t,
                        *mut libc::c_void,
                    ) = on_sigbus;
                    ours.sa_sigaction = handler as libc::sighandler_t;
                    ours.sa_flags = libc::SA_SIGINFO | libc::SA_ONSTACK;
                    libc::sigemptyset(&mut ours.sa_mask);
                    let mut before: libc::sigaction = std::mem::zeroed();
                    if page == 0 || libc::sigaction(libc::SIGBUS, &ours, &mut before) != 0 {
                        return (before, 0);
                    }
                    (before, page)
                }
            })
            .1
            != 0
    }

    /// A guarded mapping; freed on drop.
    #[derive(Debug)]
    pub struct Slot(usize);

    impl Slot {
        /// Guard `[start, start + len)`; `None` when every slot is taken.
        pub fn register(start: usize, len: usize) -> Option<Slot> {
            if start == 0 || len == 0 {
                return None;
            }
            for (i, r) in RANGES.iter().enumerate() {
                if r.len
                    .compare_exchange(0, len, Ordering::AcqRel, Ordering::Relaxed)
                    .is_ok()
                {
                    r.faulted.store(false, Ordering::Relaxed);
                    r.start.store(start, Ordering::Release);
                    return Some(Slot(i));
                }
            }
            None
        }

        /// Whether an access to the mapping faulted (a page was replaced by zeros).
        pub fn faulted(&self) -> bool {
            RANGES[self.0].faulted.load(Ordering::Acquire)
        }
    }

    impl Drop for Slot {
        fn drop(&mut self) {
            let r = &RANGES[self.0];
            r.start.store(0, Ordering::Release);
            r.len.store(0, Ordering::Release);
        }
    }

    /// A fault inside a guarded mapping: map a page of zeros over the faulting page (the access
    /// is then repeated and reads zeros) and mark the mapping. Anywhere else: the disposition
    /// from before, under which the repeated access faults again. Only atomics and system calls
    /// here (`mmap` and `sigaction` are system calls on Linux, safe in a handler in practice).
    extern "C" fn on_sigbus(_: libc::c_int, info: *mut libc::siginfo_t, _: *mut libc::c_void) {
        let Some((before, page)) = BEFORE.get() else {
            return;
        };
        // SAFETY: the kernel passes a valid siginfo for a SIGBUS delivered with SA_SIGINFO
        let addr = unsafe { (*info).si_addr() } as usize;
        for r in &RANGES {
            let start = r.start.load(Ordering::Acquire);
            let len = r.len.load(Ordering::Acquire);
            if start != 0 && addr >= start && addr - start < len {
                let at = addr & !(page - 1);
                // SAFETY: `at` is a page of a live mapping of this module (its slot is
                // registered until the map is dropped); MAP_FIXED replaces that page only
                let p = unsafe {
                    libc::mmap(
                        at as *mut libc::c_void,
                        *page,
                        libc::PROT_READ,
                        libc::MAP_PRIVATE | libc::MAP_ANONYMOUS | libc::MAP_FIXED,
                        -1,
                        0,
                    )
                };
                if p != libc::MAP_FAILED {
                    r.faulted.store(true, Ordering::Release);
                    return;
                }
            }
        }
        // SAFETY: restores the disposition saved at install
        unsafe {
            libc::sigaction(libc::SIGBUS, before, std::ptr::null_mut());
        }
    }
}
