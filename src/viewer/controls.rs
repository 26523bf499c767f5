//! The walkthrough's keys and mouse, listed once: `rrf view --help` and the overlay's help
//! are both made from [`CONTROLS`] (the window's key handling is in `window.rs`).

use std::sync::LazyLock;

/// Each control: the keys or mouse action, and what it does.
pub const CONTROLS: [(&str, &str); 19] = [
    ("W A S D", "move"),
    ("Q E", "down, up"),
    ("Shift", "faster"),
    ("wheel", "speed"),
    ("right mouse button held", "look around"),
    ("arrows, Page Up/Down", "move the selected light in its box"),
    ("L", "add a light where the selected one is"),
    ("Tab", "select the next light"),
    ("Delete", "remove it"),
    ("C", "its colour (white, warm, cool, red, green, blue)"),
    ("- =", "dim, brighten it"),
    ("1 2 3", "global, direct only, indirect only"),
    ("[ ]", "exposure"),
    ("P", "screenshot (the path is printed)"),
    ("R", "reset view and light"),
    ("O", "overlay"),
    ("U", "settings panel"),
    ("H", "show or hide this help"),
    ("Esc", "quit"),
];

/// The overlay's help: the controls as `KEYS: action`, several to a line of at most `width`
/// characters.
pub fn help_lines(width: usize) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for (keys, action) in CONTROLS {
        let entry = format!("{keys}: {action}");
        match lines.last_mut() {
            Some(line) if line.len() + 3 + entry.len() <= width => {
                line.push_str("   ");
                line.push_str(&entry);
            }
            _ => lines.push(entry),
        }
    }
    lines
}

/// The controls as `rrf view --help` lists them: one to a line, actions aligned.
pub static HELP_TEXT: LazyLock<String> = LazyLock::new(|| {
    let width = CONTROLS.iter().map(|(keys, _)| keys.len()).max().unwrap_or(0);
    CONTROLS.iter().map(|(keys, action)| format!("  {keys:<width$}  {action}\n")).collect()
});

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overlay_help_lists_every_control_within_its_width() {
        let lines = help_lines(64);
        assert!(lines.iter().all(|l| l.len() <= 64), "{lines:?}");
        let joined = lines.join("   ");
        for (keys, action) in CONTROLS {
            assert!(joined.contains(&format!("{keys}: {action}")), "{keys} missing from {lines:?}");
        }
    }
}
