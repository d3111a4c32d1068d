//! The hand-written BVH parser: the `HIERARCHY` as whitespace-separated tokens with their
//! lines, the `MOTION` block line by line, every error with its file and line and what was
//! expected; it never panics, whatever the input (see the [module docs](super) for the
//! variations it tolerates).

use glam::Vec3;

use super::{BvhClip, BvhError, BvhJoint, Channel};

/// A whitespace-separated word of the hierarchy with its 1-based line.
#[derive(Clone, Copy, Debug)]
struct Token<'a> {
    text: &'a str,
    line: usize,
}

pub(super) struct Parser<'a> {
    file: &'a str,
    /// Lines without their `\n` / `\r\n` terminators; `lines[i]` is line `i + 1`.
    lines: Vec<&'a str>,
    /// Hierarchy tokens up to and including `MOTION`.
    tokens: Vec<Token<'a>>,
    pos: usize,
}

impl<'a> Parser<'a> {
    pub(super) fn new(text: &'a str, file: &'a str) -> Self {
        let lines: Vec<&str> = text
            .split('\n')
            .map(|l| l.strip_suffix('\r').unwrap_or(l))
            .collect();
        let mut tokens = Vec::new();
        'lines: for (i, line) in lines.iter().enumerate() {
            for word in line.split_whitespace() {
                tokens.push(Token {
                    text: word,
                    line: i + 1,
                });
                if word == "MOTION" {
                    break 'lines;
                }
            }
        }
        Parser {
            file,
            lines,
            tokens,
            pos: 0,
        }
    }

    /// The line reported for "end of file": the last line of the text.
    fn eof_line(&self) -> usize {
        self.lines.len().max(1)
    }

    fn syntax(&self, line: usize, found: impl Into<String>, expected: &str) -> BvhError {
        BvhError::Syntax {
            file: self.file.to_string(),
            line,
            found: found.into(),
            expected: expected.to_string(),
        }
    }

    fn next(&mut self, expected: &str) -> Result<Token<'a>, BvhError> {
        match self.tokens.get(self.pos) {
            Some(token) => {
                self.pos += 1;
                Ok(*token)
            }
            None => Err(self.syntax(self.eof_line(), "the end of the file", expected)),
        }
    }

    fn expect(&mut self, keyword: &str, expected: &str) -> Result<Token<'a>, BvhError> {
        let token = self.next(expected)?;
        if token.text == keyword {
            Ok(token)
        } else {
            Err(self.syntax(token.line, format!("'{}'", token.text), expected))
        }
    }

    /// The words after a `ROOT` / `JOINT` keyword on its line, up to an optional `{`.
    fn name(&mut self, keyword: Token<'a>) -> Result<String, BvhError> {
        let mut words = Vec::new();
        while let Some(token) = self.tokens.get(self.pos) {
            if token.line != keyword.line || token.text == "{" {
                break;
            }
            words.push(token.text);
            self.pos += 1;
        }
        if words.is_empty() {
            return Err(self.syntax(
                keyword.line,
                format!("'{}' without a name", keyword.text),
                &format!("'{} <name>' on one line", keyword.text),
            ));
        }
        Ok(words.join(" "))
    }

    fn number(&mut self, expected: &str) -> Result<f32, BvhError> {
        let token = self.next(expected)?;
        parse_finite(token.text).ok_or_else(|| BvhError::NotANumber {
            file: self.file.to_string(),
            line: token.line,
            value: token.text.to_string(),
            expected: expected.to_string(),
        })
    }

    fn vec3(&mut self, what: &str) -> Result<Vec3, BvhError> {
        let x = self.number(&format!("the x of {what}"))?;
        let y = self.number(&format!("the y of {what}"))?;
        let z = self.number(&format!("the z of {what}"))?;
        Ok(Vec3::new(x, y, z))
    }

    pub(super) fn parse(mut self) -> Result<BvhClip, BvhError> {
        let (joints, channel_count, motion_line) = self.hierarchy()?;
        let (frame_time_s, frame_count, values) = self.motion(motion_line, channel_count)?;
        Ok(BvhClip {
            file_name: self.file.to_string(),
            joints,
            channel_count,
            frame_time_s,
            frame_count,
            values,
        })
    }

    /// Parses `HIERARCHY ... MOTION`; returns the joints, the channel count and the line of
    /// `MOTION`. Iterative, so deep nesting cannot overflow the stack.
    fn hierarchy(&mut self) -> Result<(Vec<BvhJoint>, usize, usize), BvhError> {
        self.expect("HIERARCHY", "'HIERARCHY' at the start of the file")?;
        let root = self.expect("ROOT", "'ROOT <name>' after 'HIERARCHY'")?;
        let name = self.name(root)?;
        self.expect("{", "'{' after the ROOT name")?;
        let mut joints = vec![new_joint(name, None, root.line)];
        let mut has_offset = vec![false];
        let mut stack = vec![0usize];
        let mut channel_count = 0usize;
        const BODY: &str = "'OFFSET', 'CHANNELS', 'JOINT', 'End Site' or '}' in a joint block";

        while let Some(&current) = stack.last() {
            let token = self.next(BODY)?;
            match token.text {
                "OFFSET" => {
                    if has_offset.get(current).copied().unwrap_or(true) {
                        return Err(self.syntax(
                            token.line,
                            "a second 'OFFSET' in one joint",
                            "one 'OFFSET x y z' per joint",
                        ));
                    }
                    let offset = self.vec3("OFFSET x y z")?;
                    if let (Some(joint), Some(flag)) =
                        (joints.get_mut(current), has_offset.get_mut(current))
                    {
                        joint.offset = offset;
                        *flag = true;
                    }
                }
                "CHANNELS" => {
                    let count_token = self.next("the channel count after 'CHANNELS'")?;
                    let count: usize =
                        count_token.text.parse().map_err(|_| BvhError::NotANumber {
                            file: self.file.to_string(),
                            line: count_token.line,
                            value: count_token.text.to_string(),
                            expected: "a whole channel count after 'CHANNELS'".to_string(),
                        })?;
                    if joints.get(current).is_some_and(|j| !j.channels.is_empty()) {
                        return Err(self.syntax(
                            token.line,
                            "a second 'CHANNELS' in one joint",
                            "one 'CHANNELS n ...' per joint",
                        ));
                    }
                    let mut channels = Vec::new();
                    for _ in 0..count {
                        let expected = "a channel name (Xposition, Yposition, Zposition, Xrotation, Yrotation or Zrotation)";
                        let channel_token = self.next(expected)?;
                        if channel_token.line != token.line {
                            return Err(self.syntax(
                                channel_token.line,
                                format!(
                                    "the end of the 'CHANNELS {count}' line after {} names",
                                    channels.len()
                                ),
                                &format!("{count} channel names on the CHANNELS line"),
                            ));
                        }
                        let channel = Channel::parse(channel_token.text).ok_or_else(|| {
                            self.syntax(
                                channel_token.line,
                                format!("'{}'", channel_token.text),
                                expected,
                            )
                        })?;
                        channels.push(channel);
                    }
                    if let Some(joint) = joints.get_mut(current) {
                        joint.first_channel = channel_count;
                        joint.channels = channels;
                    }
                    channel_count = channel_count.saturating_add(count);
                }
                "JOINT" => {
                    let name = self.name(token)?;
                    self.expect("{", "'{' after the JOINT name")?;
                    joints.push(new_joint(name, Some(current), token.line));
                    has_offset.push(false);
                    stack.push(joints.len() - 1);
                }
                "End" => {
                    self.expect("Site", "'Site' after 'End'")?;
                    self.expect("{", "'{' after 'End Site'")?;
                    self.expect("OFFSET", "'OFFSET x y z' in the End Site block")?;
                    let offset = self.vec3("the End Site OFFSET")?;
                    self.expect("}", "'}' closing the End Site block")?;
                    if let Some(joint) = joints.get_mut(current) {
                        if joint.end_site.is_some() {
                            return Err(self.syntax(
                                token.line,
                                "a second 'End Site' in one joint",
                                "at most one End Site per joint",
                            ));
                        }
                        joint.end_site = Some(offset);
                    }
                }
                "}" => {
                    if !has_offset.get(current).copied().unwrap_or(false) {
                        let name = joints.get(current).map_or("", |j| j.name.as_str());
                        return Err(self.syntax(
                            token.line,
                            format!("the end of joint '{name}' without an OFFSET"),
                            "'OFFSET x y z' in every joint",
                        ));
                    }
                    stack.pop();
                }
                other => {
                    let found = if other == "ROOT" {
                        "'ROOT' inside a joint block".to_string()
                    } else {
                        format!("'{other}'")
                    };
                    return Err(self.syntax(token.line, found, BODY));
                }
            }
        }

        let motion = self.expect(
            "MOTION",
            "'MOTION' after the root joint's closing '}' (one skeleton per file)",
        )?;
        if channel_count == 0 {
            return Err(self.syntax(
                motion.line,
                "a hierarchy without channels",
                "at least one 'CHANNELS' line",
            ));
        }
        let trailing = self
            .lines
            .get(motion.line - 1)
            .and_then(|l| l.split_whitespace().skip_while(|w| *w != "MOTION").nth(1));
        if let Some(word) = trailing {
            return Err(self.syntax(
                motion.line,
                format!("'{word}' after 'MOTION'"),
                "'MOTION' alone on its line",
            ));
        }
        Ok((joints, channel_count, motion.line))
    }

    /// The next non-blank line after line `after` (1-based), as (line number, text).
    fn next_line(&self, after: usize) -> Option<(usize, &'a str)> {
        self.lines
            .iter()
            .enumerate()
            .skip(after)
            .find(|(_, l)| !l.trim().is_empty())
            .map(|(i, l)| (i + 1, *l))
    }

    /// Parses `Frames:`, `Frame Time:` and the frame lines after the `MOTION` line.
    fn motion(
        &self,
        motion_line: usize,
        channel_count: usize,
    ) -> Result<(f64, usize, Vec<f32>), BvhError> {
        // "Frames:" line.
        let (frames_line, text) = self.next_line(motion_line).ok_or_else(|| {
            self.syntax(
                self.eof_line(),
                "the end of the file",
                "'Frames: <count>' after 'MOTION'",
            )
        })?;
        let normalized = normalize_spaces(text);
        let Some(count_text) = normalized.strip_prefix("Frames:") else {
            return Err(self.syntax(
                frames_line,
                format!("'{}'", clip_text(text)),
                "'Frames: <count>' after 'MOTION'",
            ));
        };
        let count_text = count_text.trim();
        let declared: usize = count_text.parse().map_err(|_| BvhError::NotANumber {
            file: self.file.to_string(),
            line: frames_line,
            value: count_text.to_string(),
            expected: "a whole number of frames after 'Frames:'".to_string(),
        })?;
        if declared == 0 {
            return Err(BvhError::NoFrames {
                file: self.file.to_string(),
                line: frames_line,
            });
        }

        // "Frame Time:" line.
        let (time_line, text) = self.next_line(frames_line).ok_or_else(|| {
            self.syntax(
                self.eof_line(),
                "the end of the file",
                "'Frame Time: <seconds>' after 'Frames:'",
            )
        })?;
        let normalized = normalize_spaces(text);
        let Some(time_text) = normalized.strip_prefix("Frame Time:") else {
            return Err(self.syntax(
                time_line,
                format!("'{}'", clip_text(text)),
                "'Frame Time: <seconds>' after 'Frames:'",
            ));
        };
        let time_text = time_text.trim();
        let frame_time_s = time_text
            .parse::<f64>()
            .ok()
            .filter(|t| t.is_finite() && *t > 0.0)
            .ok_or_else(|| {
                self.syntax(
                    time_line,
                    format!("'Frame Time: {time_text}'"),
                    "a positive number of seconds after 'Frame Time:'",
                )
            })?;

        // Frame lines.
        let remaining = self.lines.len().saturating_sub(time_line);
        let mut values = Vec::with_capacity(declared.min(remaining).saturating_mul(channel_count));
        let mut read = 0usize;
        let mut last_line = time_line;
        for (i, line) in self.lines.iter().enumerate().skip(time_line) {
            if line.trim().is_empty() {
                continue;
            }
            let line_no = i + 1;
            if read == declared {
                return Err(BvhError::ExtraFrames {
                    file: self.file.to_string(),
                    line: line_no,
                    declared,
                });
            }
            let found = line.split_whitespace().count();
            if found != channel_count {
                return Err(BvhError::ChannelCount {
                    file: self.file.to_string(),
                    line: line_no,
                    frame: read,
                    found,
                    expected: channel_count,
                });
            }
            for (column, word) in line.split_whitespace().enumerate() {
                let value = parse_finite(word).ok_or_else(|| BvhError::NotANumber {
                    file: self.file.to_string(),
                    line: line_no,
                    value: word.to_string(),
                    expected: format!("a number for channel {} of frame index {read}", column + 1),
                })?;
                values.push(value);
            }
            read += 1;
            last_line = line_no;
        }
        if read < declared {
            return Err(BvhError::Truncated {
                file: self.file.to_string(),
                line: last_line + 1,
                found: read,
                declared,
            });
        }
        Ok((frame_time_s, declared, values))
    }
}

fn new_joint(name: String, parent: Option<usize>, line: usize) -> BvhJoint {
    BvhJoint {
        name,
        parent,
        offset: Vec3::ZERO,
        channels: Vec::new(),
        first_channel: 0,
        end_site: None,
        line,
    }
}

fn parse_finite(text: &str) -> Option<f32> {
    text.parse::<f32>().ok().filter(|v| v.is_finite())
}

/// Collapses runs of whitespace to single spaces (so `Frame\tTime:` matches `Frame Time:`).
fn normalize_spaces(text: &str) -> String {
    text.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// A line shortened for an error message.
fn clip_text(text: &str) -> String {
    let trimmed = text.trim();
    match trimmed.char_indices().nth(60) {
        Some((i, _)) => format!("{}...", &trimmed[..i]),
        None => trimmed.to_string(),
    }
}
