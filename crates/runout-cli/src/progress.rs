//! The library's progress reports ([`runout::Progress`]) as indicatif bars on stderr (hidden
//! when stderr is not a terminal).

use indicatif::{ProgressBar, ProgressStyle};

/// One bar per stage, in bytes of input.
#[derive(Default)]
pub struct Bars {
    bar: Option<ProgressBar>,
}

impl runout::Progress for Bars {
    fn begin(&mut self, stage: &str, total_bytes: Option<u64>) {
        let bar = ProgressBar::new(total_bytes.unwrap_or(0));
        bar.set_style(
            ProgressStyle::with_template(
                "{msg} [{bar:40}] {bytes}/{total_bytes} ({bytes_per_sec}, {eta})",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        bar.set_message(stage.to_string());
        self.bar = Some(bar);
    }

    fn set_position(&mut self, bytes: u64) {
        if let Some(b) = &self.bar {
            b.set_position(bytes);
        }
    }

    fn advance(&mut self, bytes: u64) {
        if let Some(b) = &self.bar {
            b.inc(bytes);
        }
    }

    fn end(&mut self) {
        if let Some(b) = self.bar.take() {
            b.finish_and_clear();
        }
    }
}
