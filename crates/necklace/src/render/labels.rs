//! Where the curves' labels go: beside their curve, never over another label, the
//! legend or the view's name, and inside the view.
//!
//! Greedy, in the curves' order (the loops' order: most persistent first): a label
//! tries each of its curve's candidate points (the rightmost first, then the others
//! round the curve) on each side of it (right, left, above, below), and takes the
//! first box that is free. Where no box beside the curve is free (a crowd of loops),
//! it takes the free box nearest its rightmost point on rings of growing radius, and
//! a leader line joins it to that point. Only a view with no free room at all puts
//! a label over another.
//!
//! Conventions: canvas pixels, x to the right, y down; a box is `[x0, y0, x1, y1]`.
//! Entry point: [`place_labels`].

/// An axis-aligned box `[x0, y0, x1, y1]`.
pub type Rect = [f64; 4];

/// What a label needs: its size and the points of its curve it may sit beside (the
/// preferred one first).
#[derive(Debug, Clone, PartialEq)]
pub struct LabelRequest {
    /// Width and height of the text box.
    pub size: [f64; 2],
    /// Candidate points on the curve, preferred first; at least one.
    pub anchors: Vec<[f64; 2]>,
}

/// Where a label went.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    /// Its box.
    pub rect: Rect,
    /// The curve point a leader line joins it to, when it could not sit beside it.
    pub leader: Option<[f64; 2]>,
}

/// Boxes of labels, one per request, that overlap neither each other nor `taken`, and
/// lie inside `bounds` (see the module doc); `gap` is the distance kept from the curve
/// point, `margin` the distance kept between boxes (so that "5" and "2" side by side
/// do not read as "52").
pub fn place_labels(
    requests: &[LabelRequest],
    taken: &[Rect],
    bounds: Rect,
    gap: f64,
    margin: f64,
) -> Vec<Placement> {
    let mut occupied: Vec<Rect> = taken.to_vec();
    let mut placements = Vec::with_capacity(requests.len());
    for request in requests {
        let [w, h] = request.size;
        let free = |r: &Rect, occupied: &[Rect]| {
            inside(r, &bounds) && occupied.iter().all(|o| !overlap(&grow(r, margin), o))
        };
        let beside = request.anchors.iter().find_map(|&[x, y]| {
            [
                [x + gap, y - 0.5 * h],
                [x - gap - w, y - 0.5 * h],
                [x - 0.5 * w, y - gap - h],
                [x - 0.5 * w, y + gap],
            ]
            .into_iter()
            .map(|[x0, y0]| [x0, y0, x0 + w, y0 + h])
            .find(|r| free(r, &occupied))
        });
        let placement = match beside {
            Some(rect) => Placement { rect, leader: None },
            None => {
                let anchor = request.anchors.first().copied().unwrap_or([0.0; 2]);
                let rect = ring_search(anchor, [w, h], &bounds, gap, |r| free(r, &occupied))
                    .unwrap_or_else(|| {
                        clamp(
                            [
                                anchor[0] + gap,
                                anchor[1] - 0.5 * h,
                                anchor[0] + gap + w,
                                anchor[1] + 0.5 * h,
                            ],
                            &bounds,
                        )
                    });
                Placement {
                    rect,
                    leader: Some(anchor),
                }
            }
        };
        occupied.push(placement.rect);
        placements.push(placement);
    }
    placements
}

/// Where a curve's label may go (canvas pixels), preferred first: beside its
/// rightmost point, its leftmost, its top and bottom, then 16 points round it.
pub(super) fn label_anchors(
    points: &[[f64; 3]],
    to_canvas: &impl Fn([f64; 3]) -> [f64; 3],
) -> Vec<[f64; 2]> {
    let screen: Vec<[f64; 2]> = points
        .iter()
        .map(|&p| {
            let q = to_canvas(p);
            [q[0], q[1]]
        })
        .collect();
    let extreme = |key: fn(&[f64; 2]) -> f64| {
        screen
            .iter()
            .copied()
            .max_by(|a, b| key(a).total_cmp(&key(b)))
    };
    let mut anchors: Vec<[f64; 2]> = [
        extreme(|p| p[0]),
        extreme(|p| -p[0]),
        extreme(|p| -p[1]),
        extreme(|p| p[1]),
    ]
    .into_iter()
    .flatten()
    .collect();
    let step = screen.len().div_ceil(16).max(1);
    anchors.extend(screen.iter().step_by(step).copied());
    anchors
}

/// The first free box centred on rings of growing radius round `anchor` (24 positions
/// a ring, rings `gap + h` apart), out to the size of `bounds`.
fn ring_search(
    anchor: [f64; 2],
    [w, h]: [f64; 2],
    bounds: &Rect,
    gap: f64,
    free: impl Fn(&Rect) -> bool,
) -> Option<Rect> {
    let step = gap + h;
    let reach = (bounds[2] - bounds[0]).max(bounds[3] - bounds[1]);
    let rings = (reach / step).ceil() as usize;
    (1..=rings).find_map(|k| {
        let radius = k as f64 * step;
        (0..24).find_map(|j| {
            let angle = j as f64 * std::f64::consts::TAU / 24.0;
            let cx = anchor[0] + radius * angle.cos();
            let cy = anchor[1] + radius * angle.sin();
            let r = [cx - 0.5 * w, cy - 0.5 * h, cx + 0.5 * w, cy + 0.5 * h];
            free(&r).then_some(r)
        })
    })
}

fn overlap(a: &Rect, b: &Rect) -> bool {
    a[0] < b[2] && b[0] < a[2] && a[1] < b[3] && b[1] < a[3]
}

fn inside(r: &Rect, bounds: &Rect) -> bool {
    r[0] >= bounds[0] && r[1] >= bounds[1] && r[2] <= bounds[2] && r[3] <= bounds[3]
}

fn grow(r: &Rect, by: f64) -> Rect {
    [r[0] - by, r[1] - by, r[2] + by, r[3] + by]
}

/// `r` moved (not resized) to lie inside `bounds` where it fits.
fn clamp(r: Rect, bounds: &Rect) -> Rect {
    let dx = (bounds[0] - r[0]).max(0.0) - (r[2] - bounds[2]).max(0.0);
    let dy = (bounds[1] - r[1]).max(0.0) - (r[3] - bounds[3]).max(0.0);
    [r[0] + dx, r[1] + dy, r[2] + dx, r[3] + dy]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn disjoint(p: &[Placement], taken: &[Rect]) -> bool {
        let rects: Vec<Rect> = p
            .iter()
            .map(|p| p.rect)
            .chain(taken.iter().copied())
            .collect();
        (0..rects.len()).all(|i| (i + 1..rects.len()).all(|j| !overlap(&rects[i], &rects[j])))
    }

    #[test]
    fn labels_of_curves_at_one_place_do_not_overlap() {
        // Ten loops whose rightmost points coincide (the pretzel's "6 2 0"): every
        // label still gets its own box, inside the view, clear of the legend.
        let requests: Vec<LabelRequest> = (0..10)
            .map(|i| LabelRequest {
                size: [12.0 * (1 + i / 10) as f64, 14.0],
                anchors: vec![[300.0, 300.0], [250.0, 260.0], [200.0, 300.0]],
            })
            .collect();
        let legend = [0.0, 500.0, 200.0, 600.0];
        let bounds = [0.0, 0.0, 600.0, 600.0];
        let placed = place_labels(&requests, &[legend], bounds, 4.0, 6.0);
        assert_eq!(placed.len(), 10);
        assert!(disjoint(&placed, &[legend]));
        // And keep their margin: grown by it, they still do not touch.
        let grown: Vec<Placement> = placed
            .iter()
            .map(|p| Placement {
                rect: grow(&p.rect, 2.9),
                leader: p.leader,
            })
            .collect();
        assert!(disjoint(&grown, &[]));
        assert!(placed.iter().all(|p| inside(&p.rect, &bounds)));
        // The first takes the preferred place: right of its rightmost point.
        assert_eq!(placed[0].rect, [304.0, 293.0, 316.0, 307.0]);
        assert_eq!(placed[0].leader, None);
        // Those pushed off their curve say where they belong.
        assert!(placed.iter().skip(1).any(|p| p.leader.is_some()));
    }

    #[test]
    fn a_label_at_the_edge_of_the_view_goes_to_the_side_that_fits() {
        let requests = [LabelRequest {
            size: [20.0, 10.0],
            anchors: vec![[598.0, 100.0]],
        }];
        let placed = place_labels(&requests, &[], [0.0, 0.0, 600.0, 600.0], 3.0, 3.0);
        assert_eq!(placed[0].rect, [575.0, 95.0, 595.0, 105.0]);
    }
}
