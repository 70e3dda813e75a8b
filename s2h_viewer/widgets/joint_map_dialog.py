"""The joint map dialog: the bone of each of the hand's 21 joints, picked from the rig file's bones, for a hand
whose bones s2h does not recognise; OK only while the choice is a joint map the rig can take (the check's
message says why not)."""

from __future__ import annotations

from pathlib import Path

from PySide6.QtWidgets import QComboBox, QDialog, QDialogButtonBox, QGridLayout, QLabel, QVBoxLayout, QWidget

from s2h_viewer.errors import InputFileError
from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.rig_mapping import check_user_mapping

NO_BONE = "(none)"  # a joint left unmapped: allowed for a tip (extrapolated), an error for the others


class JointMapDialog(QDialog):
    """A drop-down of the rig's bones per joint, a row per finger, prefilled with ``initial``."""

    def __init__(self, hand_file: str | Path, bones: list[str], initial: dict[str, str], finding: str = "",
                 parent: QWidget | None = None):
        super().__init__(parent)
        self.hand_file, self.bones = Path(hand_file), list(bones)
        self.setObjectName("joint_map_dialog")
        self.setWindowTitle(f"Map the bones of {self.hand_file.name}")
        layout = QVBoxLayout(self)
        intro = QLabel((f"{finding}\n\n" if finding else "") +
                       f"Choose the bone of {self.hand_file.name} for each joint of the hand (a tip may stay "
                       f"{NO_BONE}: it is extrapolated). OK loads the hand and saves the map beside the file, where "
                       f"opening the hand again finds it.")
        intro.setWordWrap(True)
        layout.addWidget(intro)
        grid = QGridLayout()
        self.combos: dict[str, QComboBox] = {}
        rows = [("wrist", ["wrist"])] + [(f, [f"{f}_{lv}" for lv in topo.FINGER_LEVELS[f]]) for f in topo.FINGERS]
        for row, (label, joints) in enumerate(rows):
            grid.addWidget(QLabel(f"<b>{label}</b>"), row, 0)
            for column, joint in enumerate(joints):
                combo = QComboBox()
                combo.setObjectName(joint)
                combo.setToolTip(joint)
                combo.addItems([NO_BONE, *self.bones])
                combo.setCurrentText(initial.get(joint) or NO_BONE)
                combo.currentTextChanged.connect(self._check)
                if joint != "wrist":  # the row says it
                    grid.addWidget(QLabel(joint.split("_")[-1]), row, 1 + 2 * column)
                grid.addWidget(combo, row, 2 + 2 * column)
                self.combos[joint] = combo
        layout.addLayout(grid)
        self.problem = QLabel()
        self.problem.setObjectName("joint_map_problem")
        self.problem.setWordWrap(True)
        self.problem.setStyleSheet("color: #b00020")
        layout.addWidget(self.problem)
        self.buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Ok | QDialogButtonBox.StandardButton.Cancel)
        self.buttons.accepted.connect(self.accept)
        self.buttons.rejected.connect(self.reject)
        layout.addWidget(self.buttons)
        self._check()

    def mapping(self) -> dict[str, str]:
        """The joint map chosen: joint -> bone, joints left at (none) out."""
        return {joint: combo.currentText() for joint, combo in self.combos.items() if combo.currentText() != NO_BONE}

    def _check(self) -> None:
        """OK enabled only for a joint map the rig can take; else the check's message under the joints."""
        try:
            check_user_mapping(self.mapping(), self.bones, self.hand_file)
        except InputFileError as exc:
            self.problem.setText(exc.problem)
            self.buttons.button(QDialogButtonBox.StandardButton.Ok).setEnabled(False)
            return
        self.problem.setText("")
        self.buttons.button(QDialogButtonBox.StandardButton.Ok).setEnabled(True)
