//! Poses from a label column (`calibrate --pose-column NAME`): a log whose rows say which hold they
//! belong to is segmented by that label, one pose per contiguous run of equal labels, instead of by
//! the library's stillness detection. Pose segmentation, not I/O: the label of each row is taken from
//! the file line the CSV reader read that row from.

use std::path::Path;

use accelcal::accumulator::Pose;

use crate::csvio::{Table, clip, list, split_cells, split_lines};

/// The poses of `table` segmented by the column `column` of the file at `path` (the file the table was
/// read from). Each contiguous run of equal labels is one pose (mean and population variance per
/// axis); a run of a single row has no variance.
pub fn poses_by_label(table: &Table, path: &Path, column: &str) -> Result<Vec<Pose>, String> {
    let file = path.display();
    let named = clip(column);
    let index = table.header.iter().position(|h| h.trim().eq_ignore_ascii_case(column)).ok_or_else(|| {
        format!("{file}: --pose-column {named}: no such column (the header has: {})", list(&table.header))
    })?;
    // Read as the CSV reader read it: any line end, Latin-1 bytes kept as characters, quoted cells.
    let bytes = std::fs::read(path).map_err(|e| format!("{file}: {e}"))?;
    let text = String::from_utf8(bytes).unwrap_or_else(|e| e.into_bytes().iter().map(|&b| char::from(b)).collect());
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    let lines = split_lines(text);
    let mut labels = Vec::with_capacity(table.samples.len());
    for &line in &table.line_of_row {
        let cells = lines.get(line.wrapping_sub(1)).map(|l| split_cells(l, table.delimiter)).unwrap_or_default();
        let label = cells.get(index).map(|c| c.trim().to_string()).filter(|c| !c.is_empty());
        labels.push(label.ok_or_else(|| format!("{file}:{line}: --pose-column {named}: no label on this row"))?);
    }
    let mut poses = Vec::new();
    let mut start = 0;
    for i in 1..=labels.len() {
        if i == labels.len() || labels[i] != labels[start] {
            poses.push(pose_of(&table.samples[start..i], start, i));
            start = i;
        }
    }
    Ok(poses)
}

/// Mean and population variance of `rows` (rows `start..end` of the table).
fn pose_of(rows: &[[f64; 3]], start: usize, end: usize) -> Pose {
    let n = rows.len().max(1) as f64;
    let mean: [f64; 3] = std::array::from_fn(|a| rows.iter().map(|r| r[a]).sum::<f64>() / n);
    let variance: [f64; 3] = std::array::from_fn(|a| rows.iter().map(|r| (r[a] - mean[a]).powi(2)).sum::<f64>() / n);
    Pose {
        mean: mean.map(|v| v as f32),
        variance: variance.map(|v| v as f32),
        n: u32::try_from(rows.len()).unwrap_or(u32::MAX),
        start_index: u32::try_from(start).unwrap_or(u32::MAX),
        end_index: u32::try_from(end).unwrap_or(u32::MAX),
    }
}
